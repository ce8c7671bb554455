// A renderer holds only its bricks and their ghost voxels (a window of the volume). Every
// brick rendered from its window must match the same brick rendered from the whole volume:
// one sample grid per ray (set by the whole box), the same voxels under every sample.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/bricks.h"
#include "renderer/volume/backend.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

// The brick and the voxels its samples read: `ghost` beyond each face, inside the volume (one
// for trilinear sampling, two with shading: the gradient of the outer one reads one more).
VoxelBox windowOf(const BrickBox& b, const std::array<int, 3>& whole, int ghost) {
  VoxelBox w;
  for (int a = 0; a < 3; ++a) w.lo[a] = std::max(0, b.lo[a] - ghost), w.hi[a] = std::min(whole[a], b.hi[a] + ghost);
  return w;
}

BrickBox local(BrickBox b, const Volume& window) {
  for (int a = 0; a < 3; ++a) b.lo[a] -= window.origin[a], b.hi[a] -= window.origin[a];
  return b;
}

float maxAbs(const ImageF& a, const ImageF& b) {
  float m = 0;
  for (size_t i = 0; i < a.px.size(); ++i) m = std::max(m, std::fabs(a.px[i] - b.px[i]));
  return m;
}

struct WindowCase {
  const char* generator;
  BackendKind backend;
  const char* quality;
  bool shaded = false;
  // z: 0.005 makes the box a slab thinner than two steps, sampled at a step its thickness
  // sets, which a window must take from the whole volume's box, not its own.
  std::array<double, 3> spacing{1, 1.5, 1};
};

class WindowVsWhole : public ::testing::TestWithParam<WindowCase> {};

TEST_P(WindowVsWhole, EveryBrickRendersAsFromTheWholeVolume) {
  const WindowCase c = GetParam();
  const GeneratorSpec spec{c.generator, 40, 1, c.spacing};
  auto whole = std::make_shared<const Volume>(generateVolume(spec));
  const TransferFunction tf = test::defaultTf();
  Shading shading;
  shading.on = c.shaded;
  shading.specular = 0.4;  // highlights make gradient errors visible
  const auto from_whole = makeVolumeBackend(c.backend, whole, tf, shading);
  const Camera cam = Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), 5);
  const RenderOptions opt = test::options(c.quality);
  int compared = 0;
  for (int n : {2, 5}) {
    const BrickTree tree = splitBricks(*whole, n, &tf);
    for (const BrickBox& b : tree.bricks) {
      auto window = std::make_shared<const Volume>(generateVolume(spec, windowOf(b, whole->dims, c.shaded ? 2 : 1)));
      ASSERT_LT(window->voxelCount(), whole->voxelCount());
      Rect a_whole, a_window;
      const ImageF expected = from_whole->render(cam, 56, 48, b, opt, nullptr, &a_whole);
      const ImageF actual = makeVolumeBackend(c.backend, window, tf, shading)->render(cam, 56, 48, local(b, *window), opt,
                                                                             nullptr, &a_window);
      // Sample positions are computed from the window's own origin: the same point up to
      // float rounding of a coordinate below 64 (2^-18 of a voxel), far below one level.
      EXPECT_LE(maxAbs(actual, expected), 2e-4f) << test::dumpImages("window", expected, actual);
      EXPECT_LE(compare(toRGBA8(actual), toRGBA8(expected)).max_abs, 1.0 / 255 + 1e-12) << "brick " << compared;
      compared += activeRegion(expected).area() > 0;
    }
  }
  EXPECT_GE(compared, 4) << "too few bricks showed anything to compare";
}

INSTANTIATE_TEST_SUITE_P(Windows, WindowVsWhole,
                         ::testing::Values(WindowCase{"hollow-shell", BackendKind::Cpu, "default"},
                                           WindowCase{"noise-cloud", BackendKind::Cpu, "default"},
                                           WindowCase{"marschner-lobb", BackendKind::Cpu, "reference"},
                                           WindowCase{"noise-cloud", BackendKind::Osmesa, "default"},
                                           WindowCase{"hollow-shell", BackendKind::Cpu, "default", true},
                                           WindowCase{"marschner-lobb", BackendKind::Cpu, "reference", true},
                                           WindowCase{"noise-cloud", BackendKind::Cpu, "default", false, {1, 1, 0.005}},
                                           WindowCase{"noise-cloud", BackendKind::Osmesa, "default", false, {1, 1, 0.005}}),
                         [](const auto& tc) {
                           std::string s = std::string(tc.param.generator) + "_" + backendName(tc.param.backend) +
                                           "_" + tc.param.quality + (tc.param.shaded ? "_shaded" : "") +
                                           (tc.param.spacing[2] < 0.1 ? "_slab" : "");
                           std::replace(s.begin(), s.end(), '-', '_');
                           return s;
                         });

}  // namespace
}  // namespace tessera::renderer
