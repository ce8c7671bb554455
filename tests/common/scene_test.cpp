// Scene parsing: every bad input yields a SceneError naming the file and key; shipped scenes parse.
#include "common/camera.h"
#include "common/scene.h"

#include "tests/common/scene_errors.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

using namespace tessera;
namespace fs = std::filesystem;

namespace {
const char* kGood = R"(
volume: {generator: {name: hollow-shell, size: 16}}
transfer_function:
  - [0.0, 0, 0, 0, 0]
  - [1.0, 1, 1, 1, 0.5]
camera: {eye: [0, 0, 2.5], target: [0, 0, 0], up: [0, 1, 0], fov: 30}
image: [64, 48]
)";

// Replaces the first occurrence of `from` in kGood.
std::string edit(const std::string& from, const std::string& to) {
  std::string s = kGood;
  size_t p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  if (p != std::string::npos) s.replace(p, from.size(), to);
  return s;
}

using test::TempDir;
}  // namespace

TEST(Scene, ParsesGoodScene) {
  Scene s = parseScene(kGood, ".", "s.yaml");
  ASSERT_TRUE(std::holds_alternative<GeneratorSpec>(s.volume));
  EXPECT_EQ(std::get<GeneratorSpec>(s.volume).size, 16);
  EXPECT_EQ(s.width, 64);
  EXPECT_EQ(s.height, 48);
  EXPECT_EQ(s.tf.points().size(), 2u);
  EXPECT_EQ(s.quality, namedQuality("default"));
  EXPECT_EQ(loadVolume(s).voxelCount(), 16u * 16 * 16);
}

TEST(Scene, Qualities) {
  Quality r = namedQuality("reference");
  EXPECT_DOUBLE_EQ(r.step, kL0 / 16);
  EXPECT_TRUE(r.reference);
  EXPECT_FALSE(r.skip_empty);
  EXPECT_GT(r.early_termination, 1.0);
  EXPECT_DOUBLE_EQ(namedQuality("fast").step, 2 * kL0);
  Scene s = parseScene(std::string(kGood) + "quality: {step: 0.002, skip_empty: false}\n", ".", "s.yaml");
  EXPECT_EQ(s.quality.name, QualityName::Custom);
  EXPECT_DOUBLE_EQ(s.quality.step, 0.002);
  EXPECT_FALSE(s.quality.skip_empty);
  EXPECT_DOUBLE_EQ(s.quality.early_termination, namedQuality("default").early_termination);
  EXPECT_FALSE(s.quality.jitter);
  EXPECT_TRUE(parseScene(std::string(kGood) + "quality: {jitter: true}\n", ".", "s.yaml").quality.jitter);
  EXPECT_ERROR(std::string(kGood) + "quality: {jitter: 2}\n", "quality.jitter");
  EXPECT_ERROR(std::string(kGood) + "quality: {jiter: true}\n", "jiter");
  EXPECT_EQ(parseScene(std::string(kGood) + "quality: reference\n", ".", "s.yaml").quality, r);
  EXPECT_ERROR(std::string(kGood) + "quality: ultra\n", "quality: unknown quality 'ultra'");
  EXPECT_ERROR(std::string(kGood) + "quality: {step: 0}\n", "quality.step");
}

TEST(Scene, OrbitAndOrthographic) {
  Scene s = parseScene(std::string(kGood) + "orbit: {frames: 4, axis: [0, 1, 0]}\n", ".", "s.yaml");
  Camera c = s.orbit.at(s.camera, 1);
  EXPECT_NEAR(c.eye.x, 2.5, 1e-12);
  EXPECT_NEAR(c.eye.z, 0.0, 1e-12);
  Scene o = parseScene(edit("fov: 30}", "orthographic: true, height: 1.5}"), ".", "s.yaml");
  EXPECT_TRUE(o.camera.orthographic);
  EXPECT_DOUBLE_EQ(o.camera.height, 1.5);
  EXPECT_ERROR(edit("fov: 30}", "orthographic: true}"), "camera.height: missing required key");
  EXPECT_ERROR(edit("fov: 30}", "orthographic: true, height: -1}"), "height");
}

TEST(Scene, UnknownKeysNameTheirPath) {
  EXPECT_ERROR(std::string(kGood) + "colour: red\n", "colour: unknown key");
  EXPECT_ERROR(edit("fov: 30", "fov: 30, fvo: 20"), "camera.fvo: unknown key");
  EXPECT_ERROR(edit("size: 16", "size: 16, sede: 2"), "volume.generator.sede: unknown key");
  EXPECT_ERROR(std::string(kGood) + "orbit: {frames: 4, axes: [0, 1, 0]}\n", "orbit.axes: unknown key");
  EXPECT_ERROR(std::string(kGood) + "mesh: bunny.ply\n", "mesh: file not found: ");
}

TEST(Scene, MissingKeys) {
  EXPECT_ERROR(edit("eye: [0, 0, 2.5], ", ""), "camera.eye: missing required key");
  EXPECT_ERROR(edit("name: hollow-shell, ", ""), "volume.generator.name: missing required key");
  EXPECT_ERROR("volume: {file: a.raw, type: uint8}\n", "volume.dims: missing required key");
  EXPECT_ERROR("", "expected a map");
  EXPECT_ERROR("volume: [1, 2\n", "YAML syntax error");
}

TEST(Scene, AVolumeAloneGetsTheDefaultColourMapAndAFittedCamera) {
  const Scene s = parseScene("volume: {generator: {name: hollow-shell, size: 16, seed: 1}, spacing: [1, 1, 2]}\n", ".",
                             "s.yaml");
  EXPECT_EQ(s.tf, transferFunctionPreset("cool-to-warm"));
  EXPECT_EQ(s.tf.eval(0)[3], 0.0) << "the data's lowest value must be transparent";
  EXPECT_DOUBLE_EQ(s.tf.eval(1)[3], kPresetOpacity);
  // Box 0.25 x 0.25 x 0.5 (half extents): the camera looks at its centre from far enough
  // that the bounding sphere fits the 30-degree view.
  EXPECT_EQ(s.camera.target, (Vec3{0, 0, 0}));
  const double radius = std::sqrt(0.25 * 0.25 * 2 + 0.5 * 0.5);
  EXPECT_NEAR(length(s.camera.eye), 1.05 * radius / std::sin(15 * std::numbers::pi / 180), 1e-12);
  EXPECT_GT(s.camera.eye.z, 0);
  EXPECT_GT(s.camera.eye.y, 0);
  EXPECT_TRUE(s.camera_fitted) << "a tool that changes the image size fits it again";
  EXPECT_FALSE(parseScene(std::string(kGood), ".", "g.yaml").camera_fitted);
}

// A crop is what a scene without `camera` shows: the camera frames the crop's box from its
// centre, as it frames the whole box.
TEST(Scene, AFittedCameraFramesTheCrop) {
  const Scene s = parseScene("volume: {generator: {name: hollow-shell, size: 16, seed: 1}}\n"
                             "crop: {x: [0.5, 1], z: [0, 0.25]}\n", ".", "s.yaml");
  // The box is [-0.5, 0.5]^3: the crop is x 0..0.5, y -0.5..0.5, z -0.5..-0.25.
  EXPECT_EQ(s.camera.target, (Vec3{0.25, 0, -0.375}));
  const double radius = length(Vec3{0.25, 0.5, 0.125});
  EXPECT_NEAR(length(s.camera.eye - s.camera.target), 1.05 * radius / std::sin(15 * std::numbers::pi / 180), 1e-12);
  EXPECT_GT(s.camera.eye.z, s.camera.target.z) << "seen from the front, as the whole box";
}

TEST(Scene, TransferFunctionPresetsByName) {
  for (const char* name : {"cool-to-warm", "viridis", "grayscale"}) {
    const Scene s = parseScene(std::string("volume: {generator: {name: hollow-shell, size: 16}}\ntransfer_function: ") +
                                   name + "\n",
                               ".", "s.yaml");
    EXPECT_EQ(s.tf, transferFunctionPreset(name)) << name;
  }
  EXPECT_ERROR("volume: {generator: {name: hollow-shell, size: 16}}\ntransfer_function: jet\n",
               "transfer_function: unknown transfer function preset 'jet' (cool-to-warm | viridis | grayscale | ct-bone | ct-soft-tissue)");
}

TEST(Scene, EffectiveSceneYamlParsesBackToTheSameScene) {
  for (const std::string& yaml : {std::string(kGood), std::string("volume: {generator: {name: noise-cloud, size: 8}}\n"),
                                 std::string("volume: {generator: {name: hollow-shell, size: 8}}\nquality: {step: "
                                             "0.01, early_termination: 0.9, skip_empty: false, jitter: true}\norbit: "
                                             "{frames: 7}\n")}) {
    const Scene a = parseScene(yaml, ".", "a.yaml");
    const Scene b = parseScene(sceneYaml(a), ".", "b.yaml");
    EXPECT_EQ(b.tf, a.tf) << sceneYaml(a);
    EXPECT_EQ(b.camera, a.camera) << sceneYaml(a);
    EXPECT_EQ(b.quality, a.quality) << sceneYaml(a);
    EXPECT_EQ(b.width, a.width);
    EXPECT_EQ(b.height, a.height);
    EXPECT_EQ(b.orbit.frames, a.orbit.frames);
    EXPECT_EQ(std::get<GeneratorSpec>(b.volume).name, std::get<GeneratorSpec>(a.volume).name);
    EXPECT_EQ(std::get<GeneratorSpec>(b.volume).size, std::get<GeneratorSpec>(a.volume).size);
  }
}

TEST(Scene, WrongTypes) {
  EXPECT_ERROR(edit("fov: 30", "fov: abc"), "camera.fov: expected a number, got 'abc'");
  EXPECT_ERROR(edit("image: [64, 48]", "image: [64.5, 48]"), "image[0]: expected an integer, got '64.5'");
  EXPECT_ERROR(edit("image: [64, 48]", "image: 64"), "image: expected [width, height]");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5]", "eye: [0, 0]"), "camera.eye: expected a list of 3 numbers");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5]", "eye: [0, 0, .nan]"), "camera.eye[2]: expected a finite number");
  EXPECT_ERROR(edit("[1.0, 1, 1, 1, 0.5]", "[1.0, 1, 1, 1]"), "transfer_function[1]: expected a list of 5 numbers");
  EXPECT_ERROR(edit("name: hollow-shell", "name: teapot"), "volume.generator.name: unknown generator 'teapot'");
}

TEST(Scene, BadSizesAndValues) {
  EXPECT_ERROR(edit("size: 16", "size: 0"), "volume.generator.size: must be in 2..");
  EXPECT_ERROR(edit("size: 16", "size: -4"), "volume.generator.size");
  EXPECT_ERROR(edit("image: [64, 48]", "image: [0, 48]"), "image[0]: must be in 1..16384");
  EXPECT_ERROR(edit("image: [64, 48]", "image: [64, 16385]"), "image[1]: must be in 1..16384");
  EXPECT_ERROR("volume: {file: a.raw, dims: [4, 0, 4], type: uint8}\n", "volume.dims[1]: must be in 1..");
  EXPECT_ERROR("volume: {file: a.raw, dims: [4, -1, 4], type: uint8}\n", "volume.dims[1]");
  EXPECT_ERROR(edit("size: 16}", "size: 16}, spacing: [1, 0, 1]"), "volume.spacing: spacing 0 must be finite and in [1e-30, 1e30]");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5]", "eye: [0, 0, 0]"), "s.yaml: camera: eye equals target");
  EXPECT_ERROR(edit("up: [0, 1, 0]", "up: [0, 0, 3]"), "parallel");
  EXPECT_ERROR(edit("fov: 30", "fov: 180"), "camera.fov: 180 must be in [0.01, 179] degrees");
  EXPECT_ERROR(edit("[1.0, 1, 1, 1, 0.5]", "[-0.5, 1, 1, 1, 0.5]"), "transfer_function[1][0]: must be in [0, 1], got '-0.5'");
  EXPECT_ERROR(edit("[1.0, 1, 1, 1, 0.5]", "[1.0, 1, 1, 1, 1.5]"), "transfer_function[1][4]: must be in [0, 1]");
  EXPECT_ERROR(edit("[0.0, 0, 0, 0, 0]", "[0.5, 0, 0, 0, 0]\n  - [0.2, 0, 0, 0, 0]"), "transfer_function[1]: scalar '0.2' is less");
  std::string empty_tf = kGood;
  empty_tf.replace(empty_tf.find("transfer_function"), empty_tf.find("camera") - empty_tf.find("transfer_function"),
                   "transfer_function: []\n");
  EXPECT_ERROR(empty_tf, "transfer_function: expected a preset name or a non-empty list of [s, r, g, b, a], got an empty list");
  EXPECT_ERROR(std::string(kGood) + "orbit: {frames: 0}\n", "orbit.frames: must be in 1..");
}

TEST(Scene, RawFilesResolveAgainstTheSceneFolder) {
  TempDir t("scene");
  fs::create_directories(t.path / "data");
  std::vector<float> f(2 * 2 * 3, 0.5f);
  f[2 + 3] = 1.0f;
  std::ofstream((t.path / "data" / "v.raw").string(), std::ios::binary)
      .write(reinterpret_cast<const char*>(f.data()), (std::streamsize)(f.size() * 4));
  const std::string rest =
      "transfer_function: [[0, 0, 0, 0, 0], [1, 1, 1, 1, 1]]\n"
      "camera: {eye: [0, 0, 2], target: [0, 0, 0]}\n";
  std::ofstream((t.path / "good.yaml").string())
      << "volume: {file: data/v.raw, dims: [2, 2, 3], type: float32, range: [0, 2]}\n" << rest;
  Scene s = loadScene((t.path / "good.yaml").string());
  Volume v = loadVolume(s);
  EXPECT_FLOAT_EQ(v.values[5], 0.5f);  // 1.0 over range [0, 2]

  std::ofstream((t.path / "size.yaml").string())
      << "volume: {file: data/v.raw, dims: [2, 2, 2], type: float32}\n" << rest;
  try {
    loadScene((t.path / "size.yaml").string());
    FAIL() << "size mismatch accepted";
  } catch (const SceneError& e) {
    std::string m = e.what();
    EXPECT_EQ(m.rfind((t.path / "size.yaml").string(), 0), 0u) << m;
    EXPECT_NE(m.find("48 bytes"), std::string::npos) << m;
    EXPECT_NE(m.find("32 bytes"), std::string::npos) << m;
  }

  f[1 + 2 * (1 + 2 * 2)] = NAN;  // voxel (1, 1, 2), linear index 11
  std::ofstream((t.path / "data" / "v.raw").string(), std::ios::binary)
      .write(reinterpret_cast<const char*>(f.data()), (std::streamsize)(f.size() * 4));
  try {
    loadVolume(loadScene((t.path / "good.yaml").string()));
    FAIL() << "NaN accepted";
  } catch (const SceneError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find("good.yaml"), std::string::npos) << m;
    EXPECT_NE(m.find("(1, 1, 2)"), std::string::npos) << m;
    EXPECT_NE(m.find("linear index 11"), std::string::npos) << m;
  }
  EXPECT_THROW(loadScene((t.path / "absent.yaml").string()), SceneError);
  EXPECT_ERROR("volume: {file: none.raw, dims: [1, 1, 1], type: uint8}\n" + rest, "file not found");
}

TEST(Scene, ShippedScenesParse) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(TESSERA_SOURCE_DIR) / "scenes")) {
    if (e.path().extension() != ".yaml") continue;
    SCOPED_TRACE(e.path().string());
    Scene s = loadScene(e.path().string());
    EXPECT_NO_THROW(s.camera.validate());
    ++n;
  }
  EXPECT_GE(n, 3);
  Scene d = loadScene(std::string(TESSERA_SOURCE_DIR) + "/scenes/default.yaml"), b = defaultScene();
  EXPECT_EQ(d.tf, b.tf);
  EXPECT_EQ(d.camera, b.camera);
  EXPECT_EQ(d.width, b.width);
  EXPECT_EQ(d.quality, b.quality);
  EXPECT_EQ(d.orbit.frames, b.orbit.frames);
  EXPECT_EQ(std::get<GeneratorSpec>(d.volume).size, std::get<GeneratorSpec>(b.volume).size);
}

// A volume bigger than this machine is a farm's scene (each renderer loads its bricks);
// loading it whole names the bytes instead of dying of std::bad_alloc.
TEST(Scene, AVolumeBiggerThanTheMachineLoadsInWindowsAndNamesTheBytesWhole) {
  TempDir t("scene");
  const std::string f = t.write("huge.raw", "", 0);
  std::filesystem::resize_file(f, (uintmax_t)1 << 38);  // 65536 x 65536 x 64 uint8, sparse: no disk used
  const Scene s = parseScene("volume: {file: huge.raw, dims: [65536, 65536, 64], type: uint8, range: [0, 255]}\n",
                             t.path.string(), "s.yaml");
  const Volume w = loadVolume(s, VoxelBox{{1000, 2000, 10}, {1016, 2016, 20}});
  EXPECT_EQ(w.voxelCount(), 16u * 16 * 10);
  try {
    loadVolume(s);
    FAIL() << "the whole volume loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("[65536, 65536, 64] voxels need 1099511627776 bytes"), std::string::npos)
        << e.what();
  }
}

TEST(Scene, FarAwayCameraIsOutOfRangeNotParallel) {
  const std::string m = tessera::test::sceneErrorOf(edit("eye: [0, 0, 2.5]", "eye: [1e300, 0, 0]"));
  EXPECT_NE(m.find("camera.eye: distance to the target is 1e+300"), std::string::npos) << m;
  EXPECT_EQ(m.find("parallel"), std::string::npos) << m;
  EXPECT_ERROR(edit("target: [0, 0, 0]", "target: [0, 0, -1e7]"), "camera.eye: distance to the target is 10000002.5");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5], target: [0, 0, 0]", "eye: [-1e7, 0, 2.5], target: [-1e7, 0, 0]"),
               "camera.eye: coordinate -10000000 is out of range (|coordinate| <= 1000000");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5], target: [0, 0, 0]", "eye: [1e308, 0, 0], target: [-1e308, 0, 0]"),
               "camera.eye: distance to the target overflows");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5]", "eye: [0, 0, 1e-9]"), "camera.eye: distance to the target is 1e-09");
}

TEST(Scene, VolumePathThatIsNotARegularFileSaysWhatItIs) {
  TempDir t("scene");
  fs::create_directories(t.path / "data");
  const std::string dir = (t.path / "data").string();
  EXPECT_ERROR("volume: {file: " + dir + ", dims: [1, 1, 1], type: uint8}\n", "volume.file: " + dir + " is a directory");
  const std::string fifo = (t.path / "pipe").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_ERROR("volume: {file: " + fifo + ", dims: [1, 1, 1], type: uint8}\n", "volume.file: " + fifo + " is a FIFO (named pipe)");
}

TEST(Scene, AbsurdSpacingFovStepAreRefusedWithTheirLimits) {
  EXPECT_ERROR(edit("size: 16}", "size: 16}, spacing: [1, 1e-9, 1]"), "volume.spacing: spacing ratio largest/smallest is");
  EXPECT_ERROR(edit("size: 16}", "size: 16}, spacing: [1e300, 1e300, 1e300]"), "must be finite and in [1e-30, 1e30]");
  EXPECT_ERROR(edit("fov: 30", "fov: 1e-9"), "camera.fov: 1e-09 must be in [0.01, 179] degrees");
  EXPECT_ERROR(edit("fov: 30", "fov: 179.9999"), "camera.fov: 179.9999 must be in [0.01, 179] degrees");
  EXPECT_ERROR(edit("fov: 30", "orthographic: true, height: 1e-12"), "camera.height: 1e-12 must be in [1e-06, 1000000]");
  EXPECT_ERROR(std::string(kGood) + "quality: {step: 1e-8}\n",
               "quality.step: 1e-08 must be in [1.9073486328125e-06, 0.25] world units");
  EXPECT_ERROR(std::string(kGood) + "quality: {step: 1e-8}\n", "samples per ray");
  EXPECT_ERROR(std::string(kGood) + "quality: {step: 1e6}\n", "quality.step: 1000000 must be in");
  EXPECT_ERROR(std::string(kGood) + "quality: {step: 0.25}\n", "<no error>");
}

TEST(Scene, ImageLargerThanTheWireCarriesIsRefused) {
  // A whole-image rgba32f piece of 8192 x 4096 is 512 MiB, over the protocol's message limit.
  const std::string m = tessera::test::sceneErrorOf(edit("image: [64, 48]", "image: [8192, 4096]"));
  EXPECT_NE(m.find("image: 8192 x 4096 = 33554432 pixels"), std::string::npos) << m;
  EXPECT_NE(m.find("at most 16777216 pixels"), std::string::npos) << m;
  EXPECT_ERROR(edit("image: [64, 48]", "image: [4096, 4096]"), "<no error>");
}

TEST(Scene, QualityAndAntialiasingWordsRoundTrip) {
  for (QualityName q : {QualityName::Reference, QualityName::Default, QualityName::Fast})
    EXPECT_EQ(namedQuality(qualityName(q)).name, q);
  EXPECT_THROW(namedQuality("custom"), std::invalid_argument);
  EXPECT_THROW(namedQuality(QualityName::Custom), std::invalid_argument);
  for (AaMethod m : {AaMethod::None, AaMethod::Msaa, AaMethod::Ssaa, AaMethod::Fft})
    EXPECT_EQ(parseAaMethod(aaMethodName(m)), m);
  EXPECT_THROW(parseAaMethod("fxaa"), std::invalid_argument);
}

TEST(Scene, FastPresetIsFarmExact) {
  const Quality fast = namedQuality("fast"), def = namedQuality("default");
  EXPECT_EQ(fast.early_termination, def.early_termination);
  EXPECT_EQ(fast.step, 2 * def.step);
  for (const char* name : {"reference", "default", "fast"})
    for (int renderers : {1, 2, 64}) EXPECT_EQ(farmAccuracyProblem(namedQuality(name), renderers), "") << name;
}

TEST(Scene, LowEarlyTerminationIsRefusedOnlyForManyBricks) {
  Quality q = namedQuality("default");
  q.name = QualityName::Custom;
  q.early_termination = 0.95;
  EXPECT_EQ(farmAccuracyProblem(q, 1), "");  // one brick: the same rays as tessera-render
  const std::string m = farmAccuracyProblem(q, 3);
  EXPECT_NE(m.find("quality.early_termination: 0.95"), std::string::npos) << m;
  EXPECT_NE(m.find("12.75 levels"), std::string::npos) << m;
  EXPECT_NE(m.find("use >= 0.9961 or one renderer"), std::string::npos) << m;
  q.early_termination = 1 - 1.0 / 255;
  EXPECT_EQ(farmAccuracyProblem(q, 3), "");
  q.early_termination = 2;  // > 1: never terminates
  EXPECT_EQ(farmAccuracyProblem(q, 3), "");
}

TEST(Scene, ShadingOnOffOrCoefficients) {
  EXPECT_FALSE(parseScene(kGood, ".", "s.yaml").shading.on);
  const Shading on = parseScene(std::string(kGood) + "shading: true\n", ".", "s.yaml").shading;
  EXPECT_TRUE(on.on);
  EXPECT_EQ(on, (Shading{true, 0.1, 0.7, 0.2, 10}));  // VTK's defaults
  EXPECT_FALSE(parseScene(std::string(kGood) + "shading: false\n", ".", "s.yaml").shading.on);
  const Scene s = parseScene(std::string(kGood) + "shading: {ambient: 0.3, shininess: 40}\n", ".", "s.yaml");
  EXPECT_EQ(s.shading, (Shading{true, 0.3, 0.7, 0.2, 40}));
  EXPECT_EQ(parseScene(sceneYaml(s), ".", "s.yaml").shading, s.shading);  // the effective scene keeps it
  EXPECT_ERROR(std::string(kGood) + "shading: {ambient: 1.5}\n", "shading.ambient: must be in [0, 1]");
  EXPECT_ERROR(std::string(kGood) + "shading: {specular: -0.1}\n", "shading.specular: must be in [0, 1]");
  EXPECT_ERROR(std::string(kGood) + "shading: {shininess: 0}\n", "shading.shininess: must be in [1, 128]");
  EXPECT_ERROR(std::string(kGood) + "shading: {glossy: 1}\n", "shading.glossy: unknown key");
  EXPECT_ERROR(std::string(kGood) + "shading: lots\n", "shading: expected true or false, got 'lots'");
}

TEST(Scene, AMisspeltKeyGetsTheNearestKnownOne) {
  std::string misspelt = kGood;
  misspelt.replace(misspelt.find("transfer_function"), 17, "tranfer_function");
  EXPECT_ERROR(misspelt, "tranfer_function: unknown key; did you mean transfer_function? (allowed: ");
  EXPECT_ERROR(std::string(kGood) + "colour: red\n", "colour: unknown key (allowed: ");  // nothing near
}

TEST(Scene, AWrongSizeRawFileNamesBothSizesAndTheDimsThatWouldFit) {
  TempDir t("rawsize");
  const std::vector<uint16_t> voxels(4 * 4 * 3, 7);
  t.write("v.raw", voxels.data(), voxels.size() * 2);
  auto errorFor = [&](const std::string& dims) {
    try {
      parseScene("volume: {file: v.raw, dims: " + dims + ", type: uint16}\n", t.path.string(), "s.yaml");
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  const std::string fits_z = errorFor("[4, 4, 4]");
  EXPECT_NE(fits_z.find("has 96 bytes but dims x type size need 128 bytes; dims [4, 4, 3] would match"),
            std::string::npos) << fits_z;
  const std::string no_z = errorFor("[5, 4, 4]");
  EXPECT_NE(no_z.find("has 96 bytes but dims x type size need 160 bytes; check dims and type"), std::string::npos)
      << no_z;
}
