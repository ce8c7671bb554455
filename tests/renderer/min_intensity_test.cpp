// The ray caster's minimum intensity projection (blend: minimum): the maximum projection of the
// values' complements (common/max_intensity.h). Checked against what it must equal by another
// road (the maximum projection of a volume holding 1 - v), against the double-precision
// reference, the brick split against the whole volume, and skipping against none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "common/bricks.h"
#include "common/max_intensity.h"
#include "renderer/volume/raycaster.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

using test::options;

// Opaque for the low values only (0 up to 0.6, none above): rays whose smallest value stays
// above 0.6 show nothing, so bricks whose smallest voxel is above 0.6 can be passed over.
const TransferFunction kLowTf({{0, 1, 0.8, 0.2, 0.05}, {0.6, 0.2, 0.3, 0.9, 0}, {1, 0, 0, 0, 0}});

Camera minOrbitCamera(int frame) { return Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), frame); }

std::shared_ptr<const Volume> complemented(const Volume& v) {
  Volume c = v;
  for (float& x : c.values) x = 1.0f - x;
  return std::make_shared<const Volume>(std::move(c));
}

// Largest difference of value pixels' channel 0, counting pixels shown by one image only.
double valueDiff(const ImageF& a, const ImageF& b, int* shown_differently) {
  double d = 0;
  *shown_differently = 0;
  for (size_t i = 0; i < a.px.size(); i += 4) {
    if ((a.px[i + 3] > 0) != (b.px[i + 3] > 0)) ++*shown_differently;
    else d = std::max(d, (double)std::fabs(a.px[i] - b.px[i]));
  }
  return d;
}

TEST(MinIntensity, IsTheMaximumProjectionOfTheComplementedVolume) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster minimum(vol, kLowTf, {}, {0, 0, 0}, Blend::Minimum);
  const Raycaster of_complement(complemented(*vol), mirrored(kLowTf), {}, {0, 0, 0}, Blend::Maximum);
  for (int frame : {0, 5}) {
    for (const char* quality : {"default", "reference"}) {
      const ImageF a = minimum.render(minOrbitCamera(frame), 48, 40, wholeVolume(*vol), options(quality));
      const ImageF b = of_complement.render(minOrbitCamera(frame), 48, 40, wholeVolume(*vol), options(quality));
      int shown_differently = 0;
      // The complement's voxels round to 16 bits on their own: a unit apart at most.
      EXPECT_LE(valueDiff(a, b, &shown_differently), 1.5 / 65535) << quality << " frame " << frame;
      EXPECT_LE(shown_differently, 2) << quality << " frame " << frame;
      ASSERT_GT(activeRegion(a).area(), 300) << quality << " frame " << frame;
      ASSERT_LT(activeRegion(a).area(), 48 * 40) << "every ray shows: the floor is not tested";
    }
  }
}

TEST(MinIntensity, FastValuesMatchTheReferenceAndTheMappedImageTheFinerOne) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, kLowTf, {}, {0, 0, 0}, Blend::Minimum);
  const MaxIntensity map(kLowTf, true);
  RenderOptions same_step = options("reference");
  same_step.quality.step = options("default").quality.step;
  for (int frame : {0, 5}) {
    ImageF fast = rc.render(minOrbitCamera(frame), 48, 40, wholeVolume(*vol), options("default"));
    const ImageF ref = rc.render(minOrbitCamera(frame), 48, 40, wholeVolume(*vol), same_step);
    int shown_differently = 0;
    EXPECT_LT(valueDiff(fast, ref, &shown_differently), 1.0 / 65535) << "frame " << frame;
    EXPECT_LE(shown_differently, 2) << "frame " << frame;
    for (size_t i = 0; i < fast.px.size(); i += 4) {
      if (fast.px[i + 3] > 0) {
        EXPECT_GE(fast.px[i], 0.4f - 1.0f / 65535);  // 1 - m: m at most 0.6 kept
      }
    }
    // Mapped, against the reference's 16 times finer step: the accuracy contract's 40 dB.
    ImageF finer = rc.render(minOrbitCamera(frame), 48, 40, wholeVolume(*vol), options("reference"));
    map.map(fast.px.data(), fast.px.size() / 4);
    map.map(finer.px.data(), finer.px.size() / 4);
    EXPECT_GE(compare(fast, finer).psnr, 40.0) << "frame " << frame;
  }
}

TEST(MinIntensity, BricksMergedByMaximaEqualTheWholeVolume) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, kLowTf, {}, {0, 0, 0}, Blend::Minimum);
  for (int frame : {0, 3, 7}) {
    const Camera cam = minOrbitCamera(frame);
    const ImageF whole = rc.render(cam, 48, 40, wholeVolume(*vol), options("default"));
    for (int n : {2, 3, 8}) {
      const BrickTree tree = splitBricks(*vol, n, &kLowTf);
      ImageF merged(48, 40);
      for (const Brick& b : tree.bricks) {
        Rect active;
        const ImageF part = rc.render(cam, 48, 40, b, options("default"), nullptr, &active);
        compositeMaximum(merged, part, active);
      }
      EXPECT_EQ(merged, whole) << "frame " << frame << ", " << n << " bricks";
    }
  }
}

TEST(MinIntensity, SkippingChangesNoValue) {
  auto vol = test::generated("marschner-lobb", 48);
  const Raycaster rc(vol, kLowTf, {}, {0, 0, 0}, Blend::Minimum);
  RenderOptions all = options("default");
  all.quality.skip_empty = false;
  RenderStats skipping, none;
  const ImageF a = rc.render(minOrbitCamera(2), 48, 40, wholeVolume(*vol), options("default"), &skipping);
  const ImageF b = rc.render(minOrbitCamera(2), 48, 40, wholeVolume(*vol), all, &none);
  EXPECT_EQ(a, b);
  EXPECT_EQ(none.samples_skipped, 0u);
  EXPECT_LT(skipping.samples, none.samples) << "nothing passed over: skipping is not tested";
  EXPECT_EQ(skipping.samples + skipping.samples_skipped + skipping.samples_terminated,
            none.samples + none.samples_skipped + none.samples_terminated);
}

TEST(MinIntensity, ShadingIsRefused) {
  Shading lit;
  lit.on = true;
  EXPECT_THROW(Raycaster(test::generated("hollow-shell", 16), kLowTf, lit, {0, 0, 0}, Blend::Minimum),
               std::invalid_argument);
}

}  // namespace
}  // namespace tessera::renderer
