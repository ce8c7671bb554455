// Scene parsing: every bad input yields a SceneError naming the file and key; shipped scenes parse.
#include "common/scene.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

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

std::string errorOf(const std::string& yaml, const std::string& base = ".") {
  try {
    parseScene(yaml, base, "s.yaml");
  } catch (const SceneError& e) {
    std::string m = e.what();
    EXPECT_EQ(m.rfind("s.yaml: ", 0), 0u) << "message must start with the file: " << m;
    return m;
  }
  return "<no error>";
}

#define EXPECT_ERROR(yaml, text) \
  EXPECT_NE(errorOf(yaml).find(text), std::string::npos) << "want '" << text << "' in: " << errorOf(yaml)

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("tessera_scene_" + std::to_string(getpid()));
    fs::create_directories(path / "data");
  }
  ~TempDir() { fs::remove_all(path); }
};
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
  EXPECT_EQ(s.quality.name, "custom");
  EXPECT_DOUBLE_EQ(s.quality.step, 0.002);
  EXPECT_FALSE(s.quality.skip_empty);
  EXPECT_DOUBLE_EQ(s.quality.early_termination, namedQuality("default").early_termination);
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
  EXPECT_ERROR(std::string(kGood) + "mesh: bunny.ply\n", "mesh: file not found");
}

TEST(Scene, MissingKeys) {
  EXPECT_ERROR(edit("eye: [0, 0, 2.5], ", ""), "camera.eye: missing required key");
  EXPECT_ERROR(edit("name: hollow-shell, ", ""), "volume.generator.name: missing required key");
  std::string no_tf = kGood;
  no_tf.erase(no_tf.find("transfer_function"), no_tf.find("camera") - no_tf.find("transfer_function"));
  EXPECT_ERROR(no_tf, "transfer_function: missing required key");
  EXPECT_ERROR("volume: {file: a.raw, type: uint8}\n", "volume.dims: missing required key");
  EXPECT_ERROR("", "expected a map");
  EXPECT_ERROR("volume: [1, 2\n", "YAML syntax error");
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
  EXPECT_ERROR(edit("size: 16}", "size: 16}, spacing: [1, 0, 1]"), "volume.spacing[1]: spacing must be > 0");
  EXPECT_ERROR(edit("eye: [0, 0, 2.5]", "eye: [0, 0, 0]"), "s.yaml: camera: eye equals target");
  EXPECT_ERROR(edit("up: [0, 1, 0]", "up: [0, 0, 3]"), "parallel");
  EXPECT_ERROR(edit("fov: 30", "fov: 180"), "fov must be in (0, 180)");
  EXPECT_ERROR(edit("[1.0, 1, 1, 1, 0.5]", "[-0.5, 1, 1, 1, 0.5]"), "transfer_function[1][0]: must be in [0, 1], got '-0.5'");
  EXPECT_ERROR(edit("[1.0, 1, 1, 1, 0.5]", "[1.0, 1, 1, 1, 1.5]"), "transfer_function[1][4]: must be in [0, 1]");
  EXPECT_ERROR(edit("[0.0, 0, 0, 0, 0]", "[0.5, 0, 0, 0, 0]\n  - [0.2, 0, 0, 0, 0]"), "transfer_function[1]: scalar '0.2' is less");
  std::string empty_tf = kGood;
  empty_tf.replace(empty_tf.find("transfer_function"), empty_tf.find("camera") - empty_tf.find("transfer_function"),
                   "transfer_function: []\n");
  EXPECT_ERROR(empty_tf, "transfer_function: expected a non-empty list");
  EXPECT_ERROR(std::string(kGood) + "orbit: {frames: 0}\n", "orbit.frames: must be in 1..");
}

TEST(Scene, RawFilesResolveAgainstTheSceneFolder) {
  TempDir t;
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
