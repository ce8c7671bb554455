// Ray caster: sampling, ray-box intervals, quality vs reference, skipping and footprints.
#include "renderer/volume/raycaster.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/bricks.h"
#include "renderer/volume/kernels.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/tf_table.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

using test::allFinite;
using test::defaultCamera;
using test::defaultTf;
using test::generated;
using test::options;

TEST(Trilinear, ExactAtVoxelCentresAndClampedAtBorder) {
  Volume v;
  v.dims = {5, 4, 3};
  v.values.resize(v.voxelCount());
  for (size_t i = 0; i < v.values.size(); ++i) v.values[i] = (float)((i * 37) % 101) / 100.0f;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 5; ++x) EXPECT_EQ(sampleTrilinear(v, x, y, z), (double)v.at(x, y, z));
  // Half-way between two voxels along x: the mean (exact in double for these floats).
  EXPECT_NEAR(sampleTrilinear(v, 1.5, 2, 1), 0.5 * ((double)v.at(1, 2, 1) + v.at(2, 2, 1)), 1e-15);
  // Outside the voxel centres (the outer half cells) the border value holds.
  EXPECT_EQ(sampleTrilinear(v, -0.5, -0.5, -0.5), (double)v.at(0, 0, 0));
  EXPECT_EQ(sampleTrilinear(v, 4.49, 3.49, 2.49), (double)v.at(4, 3, 2));
  EXPECT_EQ(sampleTrilinear(v, -0.3, 3.4, 1), (double)v.at(0, 3, 1));
}

TEST(Trilinear, OneVoxelAxisIsConstant) {
  Volume v;
  v.dims = {3, 1, 2};
  v.values = {0.f, 0.5f, 1.f, 0.2f, 0.4f, 0.6f};
  EXPECT_EQ(sampleTrilinear(v, 1, 0.3, 0), 0.5);
  EXPECT_NEAR(sampleTrilinear(v, 2, -0.4, 0.5), 0.8, 1e-7);
}

class RayBox : public ::testing::Test {
 protected:
  Volume v = [] {
    Volume x;
    x.dims = {8, 8, 8};
    x.values.assign(512, 0.f);
    return x;
  }();
  VolumeGeometry g{v};
  BrickBox whole{{0, 0, 0}, {8, 8, 8}};
};

TEST_F(RayBox, ParallelToAnAxis) {
  double t0, t1;
  ASSERT_TRUE(boxInterval(g, Ray{{0.1, 0.2, 2.0}, {0, 0, -1}}, whole, t0, t1));
  EXPECT_DOUBLE_EQ(t0, 1.5);
  EXPECT_DOUBLE_EQ(t1, 2.5);
  EXPECT_FALSE(boxInterval(g, Ray{{0.6, 0.2, 2.0}, {0, 0, -1}}, whole, t0, t1));
}

TEST_F(RayBox, GrazingFacesAreHalfOpen) {
  double t0, t1;
  // Along the min faces x = y = -0.5: inside (half-open [lo, hi) boxes include lo).
  EXPECT_TRUE(boxInterval(g, Ray{{-0.5, -0.5, 2.0}, {0, 0, -1}}, whole, t0, t1));
  // Along the max face x = +0.5: outside, so the brick on the far side of an inner face
  // owns the ray exactly once.
  EXPECT_FALSE(boxInterval(g, Ray{{0.5, 0.0, 2.0}, {0, 0, -1}}, whole, t0, t1));
  // Through an edge diagonally: touches a single point, empty half-open interval.
  const double s = std::sqrt(0.5);
  EXPECT_FALSE(boxInterval(g, Ray{{-1.0, 0.0, 1.0}, {s, 0, -s}}, BrickBox{{0, 0, 0}, {4, 8, 4}}, t0, t1) && t1 > t0 + 1e-12);
}

TEST_F(RayBox, EyeInsideStartsAtTheEye) {
  RaySpan span;
  const double step = kL0;
  ASSERT_TRUE(raySpan(g, Ray{{0.0, 0.0, 0.0}, {0, 0, 1}}, whole, step, span));
  EXPECT_EQ(span.t0, 0.0);
  EXPECT_EQ(span.k_first, 0);
  EXPECT_EQ(span.k_end, 128);  // t_k = (k + 0.5)/256 < 0.5
}

TEST_F(RayBox, BricksPartitionTheSampleGrid) {
  // Every sample of the whole-volume span belongs to exactly one brick of a 3x2x2 split.
  std::vector<BrickBox> bricks;
  for (int x : {0, 3, 5})
    for (int y : {0, 4})
      for (int z : {0, 1}) bricks.push_back({{x, y, z * 5}, {x == 0 ? 3 : x == 3 ? 5 : 8, y + 4, z ? 8 : 5}});
  uint32_t seed = 7;
  auto rnd = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  for (int i = 0; i < 2000; ++i) {
    Vec3 o{rnd() * 3 - 1.5, rnd() * 3 - 1.5, rnd() * 3 - 1.5};
    Vec3 d = normalize(Vec3{rnd() - 0.5, rnd() - 0.5, rnd() - 0.5});
    if (i % 10 == 0) d = Vec3{0, 0, o.z > 0 ? -1.0 : 1.0};  // axis-parallel rays too
    RaySpan w;
    const bool hit = raySpan(g, Ray{o, d}, whole, 0.013, w);
    std::vector<int> owner(hit ? w.k_end : 0, 0);
    for (const BrickBox& b : bricks) {
      RaySpan s;
      if (!raySpan(g, Ray{o, d}, b, 0.013, s)) continue;
      ASSERT_TRUE(hit);
      ASSERT_EQ(s.t0, w.t0);
      for (int64_t k = s.k_first; k < s.k_end; ++k) owner[k]++;
    }
    for (int64_t k = hit ? w.k_first : 0; k < (hit ? w.k_end : 0); ++k) ASSERT_EQ(owner[k], 1) << "ray " << i << " k " << k;
  }
}

TEST(TfTable, ErrorAgainstExactClassificationIsSmall) {
  // The 4096-entry table interpolates linearly between entries h = 1/4095 apart; the error
  // peaks where a TF kink falls between entries: h * |slope change| / 4 = 2.4e-4 * 1.63 / 4
  // = 1.0e-4 at s = 0.7 for the default TF (measured 1.0e-4). Elsewhere it is ~1e-7.
  const TransferFunction tf = defaultTf();
  const TfTable tab(tf, kL0);
  const double worst = test::tableError(tab, tf, 0, 1, 100000);
  EXPECT_LT(worst, 1.1e-4);
  RecordProperty("tf_table_max_error", std::to_string(worst));
}

// docs/DESIGN.md accuracy contract: default volume quality vs reference PSNR >= 40 dB.
class GeneratorQuality : public ::testing::TestWithParam<std::string> {};

TEST_P(GeneratorQuality, DefaultMatchesReference) {
  auto vol = generated(GetParam(), 40);
  const Raycaster rc(vol, defaultTf());
  const ImageF def = rc.render(defaultCamera(), 48, 48, wholeVolume(*vol), options("default"));
  const ImageF ref = rc.render(defaultCamera(), 48, 48, wholeVolume(*vol), options("reference"));
  ASSERT_TRUE(allFinite(def));
  ASSERT_TRUE(allFinite(ref));
  ASSERT_GT(activeRegion(ref).area(), 100);  // the scene is not empty
  const ImageError e = compare(def, ref);
  EXPECT_GE(e.psnr, 40.0) << "max_abs " << e.max_abs << " see " << test::dumpImages("quality_" + GetParam(), ref, def);
}

INSTANTIATE_TEST_SUITE_P(AllGenerators, GeneratorQuality,
                         ::testing::Values("hollow-shell", "marschner-lobb", "noise-cloud"));

TEST(Skipping, IdenticalImageAndSkipsSamples) {
  for (const char* name : {"hollow-shell", "marschner-lobb", "noise-cloud"}) {
    auto vol = generated(name, 48);
    const Raycaster rc(vol, defaultTf());
    RenderOptions on = options("default"), off = options("default");
    off.quality.skip_empty = false;
    for (int frame : {0, 7}) {
      const Camera cam = Orbit{30, {0.3, 1, 0.2}}.at(defaultCamera(), frame);
      RenderStats s_on, s_off;
      const ImageF a = rc.render(cam, 64, 48, wholeVolume(*vol), on, &s_on);
      const ImageF b = rc.render(cam, 64, 48, wholeVolume(*vol), off, &s_off);
      EXPECT_TRUE(a == b) << name << " frame " << frame << ": skipping changed the image";
      EXPECT_EQ(s_off.samples_skipped, 0u);
      if (std::string(name) == "hollow-shell") {
        EXPECT_GT(3 * s_on.samples_skipped, s_on.samples) << "a third of the shell samples lie in empty blocks at 48^3";
      }
      // Skipping only removes samples: taken + skipped never exceeds the unskipped total.
      EXPECT_LE(s_on.samples + s_on.samples_skipped, s_off.samples + 8 * 64 * 48) << name;
    }
  }
}

// A slice far thinner than the step: the named qualities sample it twice across (at their
// own step most rays would pass it between two samples and the image would be empty), as
// the reference does, and bricks of it composite to the whole.
TEST(ThinVolume, ASliceIsSampledAcrossAndMatchesTheReference) {
  auto vol = test::slice();
  const Raycaster rc(vol, test::opaqueTf());
  for (const char* quality : {"default", "fast"}) {
    const ImageF img = rc.render(defaultCamera(), 64, 48, wholeVolume(*vol), options(quality));
    const ImageF ref = rc.render(defaultCamera(), 64, 48, wholeVolume(*vol), options("reference"));
    ASSERT_GT(activeRegion(ref).area(), 1000);
    ASSERT_GT(activeRegion(img).area(), 1000) << quality << ": the slice was not sampled";
    const ImageError e = compare(img, ref);
    EXPECT_GE(e.psnr, 40.0) << quality << " max_abs " << e.max_abs << " see "
                            << test::dumpImages(std::string("thin_") + quality, ref, img);
  }
  const ImageF whole = rc.render(defaultCamera(), 64, 48, wholeVolume(*vol), options("default"));
  const TransferFunction tf = test::opaqueTf();
  const BrickTree tree = splitBricks(*vol, 3, &tf);
  ImageF out(64, 48);
  for (int leaf : tree.visibilityOrder(*vol, defaultCamera())) {
    Rect act;
    const ImageF part = rc.render(defaultCamera(), 64, 48, tree.bricks[leaf], options("default"), nullptr, &act);
    if (!act.empty()) compositeOver(out, part, act);
  }
  EXPECT_LE(compare(out, whole).max_abs, 1.0 / 255);
}

// The step of a thin volume: half its thinnest side, never below the scene's least step;
// a window takes it from the whole volume's box; a volume thicker than two steps keeps it.
TEST(ThinVolume, TheStepIsHalfTheThinnestSideAndNoLessThanTheLeastStep) {
  Volume v;
  v.dims = {64, 64, 1};  // 4 steps thick: unchanged
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("default"), v).step, kL0);
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("fast"), v).step, 0.5 / 64);
  v.dims = {512, 512, 1};
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("default"), v).step, 0.5 / 512);
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("reference"), v).step, kL0 / 16);
  v.dims = {64, 8, 1};
  v.whole_dims = {512, 512, 1};  // a window of the 512 x 512 slice
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("default"), v).step, 0.5 / 512);
  Volume sheet;
  sheet.dims = {8192, 8192, 1};
  sheet.spacing = {1, 1, 0.01};
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("default"), sheet).step, kMinStep);
  Volume cube;
  cube.dims = {256, 256, 256};
  EXPECT_DOUBLE_EQ(samplingQuality(namedQuality("fast"), cube).step, 2 * kL0);
}

TEST(Threads, ResultIndependentOfThreadCount) {
  auto vol = generated("noise-cloud", 32);
  const Raycaster rc(vol, defaultTf());
  const ImageF one = rc.render(defaultCamera(), 70, 50, wholeVolume(*vol), options("default", 1));
  const ImageF three = rc.render(defaultCamera(), 70, 50, wholeVolume(*vol), options("default", 3));
  EXPECT_TRUE(one == three);
}

TEST(Footprint, PixelsOutsideTheBrickAreUntouchedAndActiveIsTight) {
  auto vol = test::constant({32, 32, 32}, 0.8f);
  const Raycaster rc(vol, defaultTf());
  const Brick corner{{0, 0, 0}, {8, 8, 8}};  // the lower-left-back corner of the box
  Rect active;
  const ImageF img = rc.render(Camera{{0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 30, false, 1}, 64, 64, corner,
                               options("default"), nullptr, &active);
  EXPECT_EQ(active, activeRegion(img));
  ASSERT_FALSE(active.empty());
  // The brick spans x,y in [-0.5,-0.25] (world): bottom-left quadrant of the image only.
  EXPECT_LT(active.x + active.w, 32);
  EXPECT_GE(active.y, 32);
}

TEST(Errors, InvalidArgumentsThrow) {
  auto vol = generated("hollow-shell", 16);
  const Raycaster rc(vol, defaultTf());
  EXPECT_THROW(rc.render(defaultCamera(), 0, 10, wholeVolume(*vol), options("default")), std::invalid_argument);
  EXPECT_THROW(rc.render(defaultCamera(), 10, 10, Brick{{0, 0, 0}, {17, 16, 16}}, options("default")), std::invalid_argument);
  RenderOptions bad = options("default");
  bad.quality.step = 0;
  EXPECT_THROW(rc.render(defaultCamera(), 10, 10, wholeVolume(*vol), bad), std::invalid_argument);
  Camera c = defaultCamera();
  c.target = c.eye;
  EXPECT_THROW(rc.render(c, 10, 10, wholeVolume(*vol), options("default")), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::renderer
