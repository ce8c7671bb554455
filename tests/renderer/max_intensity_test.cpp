// The ray caster's maximum intensity projection (blend: maximum, renderer/volume/max_kernel.cpp):
// value pixels against the double-precision reference, the brick split against the whole
// volume, skipping against none, and the floor below which nothing shows.
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

// 0 up to 0.4 (the floor), then a ramp: the Marschner-Lobb volume's values span 0..1.
const TransferFunction kTf({{0, 0, 0, 0, 0}, {0.4, 0.2, 0.3, 0.9, 0}, {1, 1, 0.8, 0.2, 0.05}});

Camera orbitCamera(int frame) { return Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), frame); }

// Orthographic, looking down -z from a hair (`tilt`) off the axis.
Camera alongZ(double tilt, double height) {
  Camera cam;
  cam.eye = {tilt, 0.5 * tilt, 3};
  cam.target = {0, 0, 0};
  cam.orthographic = true;
  cam.height = height;
  return cam;
}

// Largest difference of value pixels' s (channel 0) and whether the same pixels show.
double maxValueDiff(const ImageF& a, const ImageF& b, int* shown_differently) {
  double d = 0;
  *shown_differently = 0;
  for (size_t i = 0; i < a.px.size(); i += 4) {
    if ((a.px[i + 3] > 0) != (b.px[i + 3] > 0)) ++*shown_differently;
    else d = std::max(d, (double)std::fabs(a.px[i] - b.px[i]));
  }
  return d;
}

// The fast kernel (default quality) against the reference at the same step, whole volume:
// both images, their largest value difference and the pixels shown by one only.
struct AgainstReference {
  ImageF fast, ref;
  double diff = 0;
  int shown_differently = 0;
};
AgainstReference againstReference(const Raycaster& rc, const Volume& v, const Camera& cam, int w, int h,
                                  RenderStats* fast_stats = nullptr) {
  RenderOptions same_step = options("reference");
  same_step.quality.step = options("default").quality.step;
  AgainstReference r;
  r.fast = rc.render(cam, w, h, wholeVolume(v), options("default"), fast_stats);
  r.ref = rc.render(cam, w, h, wholeVolume(v), same_step);
  r.diff = maxValueDiff(r.fast, r.ref, &r.shown_differently);
  return r;
}

TEST(MaxIntensity, FastValuesMatchTheReferenceWithinTheSixteenBitQuantization) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  for (int frame : {0, 5}) {
    const AgainstReference r = againstReference(rc, *vol, orbitCamera(frame), 48, 40);
    const ImageF& fast = r.fast;
    ASSERT_GT(activeRegion(r.ref).area(), 600);
    // Voxels are kept as round(v * 65535): half a unit, and float interpolation's error.
    EXPECT_LT(r.diff, 1.0 / 65535) << "frame " << frame;
    // Rays whose largest value lies within that error of the floor may show on one side only.
    EXPECT_LE(r.shown_differently, 2) << "frame " << frame;
    for (size_t i = 0; i < fast.px.size(); i += 4) {
      if (fast.px[i + 3] == 0) continue;
      EXPECT_EQ(fast.px[i + 3], 1.0f);  // value pixels: (s, 0, 0, 1)
      EXPECT_EQ(fast.px[i + 1], 0.0f);
      EXPECT_GE(fast.px[i], 0.4f - 1.0f / 65535);  // nothing below the floor is kept
    }
  }
}

// Against the reference's 16 times finer step (maxima between the default step's samples), the
// mapped images agree as the accuracy contract asks of the default quality.
TEST(MaxIntensity, MappedImagesAreWithinTheContractOfTheFinerReference) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  const MaxIntensity map(kTf);
  for (int frame : {0, 5}) {
    ImageF fast = rc.render(orbitCamera(frame), 48, 40, wholeVolume(*vol), options("default"));
    ImageF ref = rc.render(orbitCamera(frame), 48, 40, wholeVolume(*vol), options("reference"));
    map.map(fast.px.data(), fast.px.size() / 4);
    map.map(ref.px.data(), ref.px.size() / 4);
    ASSERT_GT(activeRegion(ref).area(), 600);
    EXPECT_GE(compare(fast, ref).psnr, 40.0) << "frame " << frame;
  }
}

// Rays along an axis and a hair off it: the kernel jumps to the last sample of a brick that
// cannot raise the maximum, and a ray that barely moves across on an axis must not jump past
// that axis' brick boundary. Every value must equal the unskipped reference's at the same step.
TEST(MaxIntensity, BrickJumpsMissNoValueOnRaysNearlyAlongAnAxis) {
  // The shell's front reaches the maximum its back cannot raise: most samples are jumped over.
  auto vol = test::generated("hollow-shell", 48);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  for (const double tilt : {0.0, 1e-7, 1e-4, 3e-3}) {
    RenderStats st;
    const AgainstReference r = againstReference(rc, *vol, alongZ(tilt, 0.9), 40, 40, &st);
    EXPECT_LT(r.diff, 1.0 / 65535) << "tilt " << tilt;
    EXPECT_LE(r.shown_differently, 2) << "tilt " << tilt;
    EXPECT_GT(st.samples_skipped, st.samples / 4) << "tilt " << tilt << ": no jumps to test";
  }
}

// A plateau at 0.5 fills the first brick a ray down -z meets (voxels 24..32), so the kernel jumps
// to that brick's last sample; the brightest voxel, at z = 23, is the first of the next brick. At
// one voxel a step, samples down z land on voxel centres: a jump two samples too far misses it.
TEST(MaxIntensity, ABrickJumpStopsBeforeTheNextBricksFirstSample) {
  Volume v = *test::constant({8, 8, 256}, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      for (int z = 26; z <= 30; ++z) v.values[v.index(x, y, z)] = 0.5f;
      v.values[v.index(x, y, 23)] = 1.0f;
    }
  auto vol = std::make_shared<const Volume>(v);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  for (const double tilt : {0.0, 1e-6, 1e-3}) {
    RenderStats st;
    const AgainstReference r = againstReference(rc, *vol, alongZ(tilt, 0.025), 16, 16, &st);  // 1/32 wide
    EXPECT_LT(r.diff, 1.0 / 65535) << "tilt " << tilt;
    EXPECT_EQ(r.shown_differently, 0) << "tilt " << tilt;
    EXPECT_GT(r.fast.at(8, 8)[0], 0.75f) << "tilt " << tilt;  // the bright voxel's samples
    EXPECT_GT(st.samples_skipped, 0u) << "tilt " << tilt << ": no jump to test";
  }
}

TEST(MaxIntensity, BricksMergedByMaximaEqualTheWholeVolume) {
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  for (int frame : {0, 3, 7}) {
    const Camera cam = orbitCamera(frame);
    const ImageF whole = rc.render(cam, 48, 40, wholeVolume(*vol), options("default"));
    for (int n : {2, 3, 8}) {
      const BrickTree tree = splitBricks(*vol, n, &kTf);
      ImageF merged(48, 40);
      for (const Brick& b : tree.bricks) {  // any order: the maximum does not care
        Rect active;
        const ImageF part = rc.render(cam, 48, 40, b, options("default"), nullptr, &active);
        compositeMaximum(merged, part, active);
      }
      EXPECT_EQ(merged, whole) << "frame " << frame << ", " << n << " bricks";
    }
  }
}

TEST(MaxIntensity, SkippingChangesNoValue) {
  auto vol = test::generated("hollow-shell", 48);
  const Raycaster rc(vol, kTf, {}, {0, 0, 0}, Blend::Maximum);
  RenderOptions all = options("default");
  all.quality.skip_empty = false;
  RenderStats skipping, none;
  const ImageF a = rc.render(orbitCamera(2), 48, 40, wholeVolume(*vol), options("default"), &skipping);
  const ImageF b = rc.render(orbitCamera(2), 48, 40, wholeVolume(*vol), all, &none);
  EXPECT_EQ(a, b);
  // Without skipping every sample is interpolated; with it, bricks below the floor are cut
  // off and bricks that cannot raise a ray's maximum passed over, and not a value changes.
  EXPECT_EQ(none.samples_skipped, 0u);
  EXPECT_LT(skipping.samples, none.samples * 3 / 4) << skipping.samples << " of " << none.samples;  // 62% here
  EXPECT_EQ(skipping.samples + skipping.samples_skipped + skipping.samples_terminated,
            none.samples + none.samples_skipped + none.samples_terminated);
}

TEST(MaxIntensity, AColourMapWithoutOpacityShowsNothing) {
  auto vol = test::generated("hollow-shell", 24);
  const TransferFunction clear({{0, 1, 1, 1, 0}, {1, 1, 1, 1, 0}});
  const Raycaster rc(vol, clear, {}, {0, 0, 0}, Blend::Maximum);
  EXPECT_TRUE(activeRegion(rc.render(orbitCamera(0), 24, 24, wholeVolume(*vol), options("default"))).empty());
  EXPECT_TRUE(activeRegion(rc.render(orbitCamera(0), 24, 24, wholeVolume(*vol), options("reference"))).empty());
  // Without skipping every ray is cast, and each must still show nothing (its floor is beyond
  // every value: it once returned a value pixel of alpha 1, and a farm sent it as a whole piece).
  RenderOptions all = options("default");
  all.quality.skip_empty = false;
  RenderStats stats;
  EXPECT_TRUE(activeRegion(rc.render(orbitCamera(0), 24, 24, wholeVolume(*vol), all, &stats)).empty());
  EXPECT_EQ(stats.samples, 0u);
  EXPECT_GT(stats.samples_skipped, 0u);
}

TEST(MaxIntensity, ShadingIsRefused) {
  Shading lit;
  lit.on = true;
  EXPECT_THROW(Raycaster(test::generated("hollow-shell", 16), kTf, lit, {0, 0, 0}, Blend::Maximum), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::renderer
