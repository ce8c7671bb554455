// The scene's `crop`: the key, its voxel box, and every backend cutting each brick to it, so
// that the whole volume cropped is the crop box rendered, and a renderer's window renders its
// brick cropped as the whole volume does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/bricks.h"
#include "renderer/volume/backend.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

float maxAbs(const ImageF& a, const ImageF& b) {
  float m = 0;
  for (size_t i = 0; i < a.px.size(); ++i) m = std::max(m, std::fabs(a.px[i] - b.px[i]));
  return m;
}

Crop cropOf(std::array<double, 2> x, std::array<double, 2> y, std::array<double, 2> z) {
  Crop c;
  c.axes = {x, y, z};
  return c;
}

TEST(Crop, TheKeyItsVoxelsAndItsErrors) {
  const Scene s = parseScene("volume: {generator: {name: hollow-shell, size: 16}}\ncrop: {x: [0.25, 0.75], z: [0, 0.5]}\n", ".");
  EXPECT_EQ(s.crop, cropOf({0.25, 0.75}, {0, 1}, {0, 0.5}));
  EXPECT_EQ(parseScene(sceneYaml(s), ".").crop, s.crop) << sceneYaml(s);
  EXPECT_NE(sceneIdentity(s), sceneIdentity(parseScene("volume: {generator: {name: hollow-shell, size: 16}}\n", ".")));
  const VoxelBox b = cropBox(s.crop, {16, 10, 7});
  EXPECT_EQ(b, (VoxelBox{{4, 0, 0}, {12, 10, 4}}));  // faces at the nearest voxel boundary (3.5 -> 4)
  EXPECT_EQ(cropBox(cropOf({0.5, 0.51}, {0, 1}, {0, 1}), {16, 8, 8}), (VoxelBox{{8, 0, 0}, {9, 8, 8}}))
      << "at least one voxel";
  const std::string volume = "volume: {generator: {name: hollow-shell, size: 16}}\n";
  for (const auto& [text, says] : std::vector<std::pair<std::string, std::string>>{
           {volume + "crop: {x: [0.5, 0.5]}", "crop.x: [0.5, 0.5]: expected 0 <= lo < hi <= 1"},
           {volume + "crop: {y: [-0.1, 0.5]}", "crop.y: [-0.1, 0.5]"},
           {volume + "crop: {w: [0, 1]}", "crop.w"},
           {volume + "crop: [0, 1]", "crop: expected a map"},
           {"mesh: {isosurface: {of: volume, level: 0.5}}\n" + volume + "crop: {x: [0, 1]}", "crop: cuts the rendered volume"}}) {
    try {
      parseScene(text, ".", "s.yaml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  }
}

class CropBackends : public ::testing::TestWithParam<BackendKind> {};

// The whole volume cropped is the crop box rendered by the backend itself, to the bit.
TEST_P(CropBackends, TheCroppedVolumeIsTheCropBoxRendered) {
  auto v = test::generated("hollow-shell", 40);
  const TransferFunction tf = test::defaultTf();
  const Crop crop = cropOf({0.2, 0.7}, {0, 0.6}, {0.3, 1});
  const Camera cam = Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), 2);
  const RenderOptions opt = test::options("default");
  const auto plain = makeVolumeBackend(GetParam(), v, tf);
  const auto cropped = makeVolumeBackend(GetParam(), v, tf, {}, {0, 0, 0}, Blend::Composite, crop);
  const ImageF whole = plain->render(cam, 64, 48, wholeVolume(*v), opt);
  const ImageF expected = plain->render(cam, 64, 48, cropBox(crop, v->dims), opt);
  const ImageF actual = cropped->render(cam, 64, 48, wholeVolume(*v), opt);
  EXPECT_EQ(maxAbs(actual, expected), 0.0f) << test::dumpImages("crop", expected, actual);
  EXPECT_GT(maxAbs(actual, whole), 0.1f) << "the crop changed nothing: the test proves nothing";
  EXPECT_GT(activeRegion(toRGBA8(actual)).area(), 200) << "the crop left (nearly) nothing";
  // A brick wholly outside the crop: transparent, nothing active.
  Rect active{1, 1, 1, 1};
  const ImageF outside = cropped->render(cam, 64, 48, BrickBox{{0, 0, 0}, {5, 40, 40}}, opt, nullptr, &active);
  EXPECT_EQ(active.area(), 0);
  EXPECT_EQ(*std::max_element(outside.px.begin(), outside.px.end()), 0.0f);
}

// A crop one voxel thin, seen face on: the step shrinks to half its thickness, so every ray
// samples across it (at the scene's step most rays passed between two samples: empty image).
TEST_P(CropBackends, ASlabOneVoxelThinIsSampledAcross) {
  // 300 slices: one is 1/300 of the box thick, under the scene's step of 1/256; face on, every
  // ray of a slab has the same phase, so a slab is drawn whole or not at all.
  auto v = test::constant({16, 16, 300}, 0.6f);
  const TransferFunction tf({{0, 0.9, 0.6, 0.5, 0}, {1, 1, 1, 1, 0.9}});
  Camera cam = test::defaultCamera();
  cam.eye = {0, 0, 3}, cam.target = {0, 0, 0}, cam.up = {0, 1, 0};
  cam.orthographic = true, cam.height = 0.05;
  for (int k = 140; k < 160; ++k) {
    const Crop crop = cropOf({0, 1}, {0, 1}, {k / 300.0, (k + 1) / 300.0});
    ASSERT_EQ(cropBox(crop, v->dims).lo[2], k);
    ASSERT_EQ(cropBox(crop, v->dims).hi[2], k + 1);
    const auto cropped = makeVolumeBackend(GetParam(), v, tf, {}, {0, 0, 0}, Blend::Composite, crop);
    const ImageF fast = cropped->render(cam, 24, 24, wholeVolume(*v), test::options("default"));
    const ImageF ref = makeVolumeBackend(BackendKind::Cpu, v, tf, {}, {0, 0, 0}, Blend::Composite, crop)
                           ->render(cam, 24, 24, wholeVolume(*v), test::options("reference"));
    EXPECT_EQ(activeRegion(toRGBA8(fast)).area(), 24 * 24) << "slice " << k << test::dumpImages("thin_crop", ref, fast);
    EXPECT_GT(ref.at(12, 12)[3], 0.05f) << "the reference shows slice " << k;
    EXPECT_LE(maxAbs(fast, ref), 0.05f) << "slice " << k << test::dumpImages("thin_crop", ref, fast);
  }
}

INSTANTIATE_TEST_SUITE_P(Both, CropBackends, ::testing::Values(BackendKind::Cpu, BackendKind::Osmesa),
                         [](const auto& p) { return std::string(backendName(p.param)); });

// A renderer holds its bricks' window of the volume: the crop is in the whole volume's voxels
// and each brick, cut to it there, renders as from the whole volume.
TEST(Crop, EachBrickFromItsWindowAsFromTheWholeVolume) {
  const GeneratorSpec spec{"noise-cloud", 40, 1, {1, 1.5, 1}};
  auto whole = std::make_shared<const Volume>(generateVolume(spec));
  const TransferFunction tf = test::defaultTf();
  const Crop crop = cropOf({0.1, 0.6}, {0.3, 0.9}, {0, 0.8});
  const auto from_whole = makeVolumeBackend(BackendKind::Cpu, whole, tf, {}, {0, 0, 0}, Blend::Composite, crop);
  const Camera cam = Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), 5);
  const RenderOptions opt = test::options("default");
  int shown = 0;
  for (const BrickBox& b : splitBricks(*whole, 5, &tf).bricks) {
    VoxelBox w;  // the brick and one ghost voxel beyond each face, inside the volume
    for (int a = 0; a < 3; ++a) w.lo[a] = std::max(0, b.lo[a] - 1), w.hi[a] = std::min(whole->dims[a], b.hi[a] + 1);
    auto window = std::make_shared<const Volume>(generateVolume(spec, w));
    BrickBox local = b;
    for (int a = 0; a < 3; ++a) local.lo[a] -= w.lo[a], local.hi[a] -= w.lo[a];
    const ImageF expected = from_whole->render(cam, 56, 48, b, opt);
    const ImageF actual = makeVolumeBackend(BackendKind::Cpu, window, tf, {}, {0, 0, 0}, Blend::Composite, crop)
                              ->render(cam, 56, 48, local, opt);
    EXPECT_LE(maxAbs(actual, expected), 2e-4f) << test::dumpImages("crop_window", expected, actual);
    shown += activeRegion(toRGBA8(expected)).area() > 0;
  }
  EXPECT_GE(shown, 3) << "too few bricks showed anything to compare";
}

}  // namespace
}  // namespace tessera::renderer
