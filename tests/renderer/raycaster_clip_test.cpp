// Clipping rays to the box that can be non-empty: the box bounds exactly the non-empty
// blocks, a clipped span keeps the global sample grid, and images and sample totals are
// the same with skipping (and so clipping) on and off; rays cast in pairs match single rays.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "common/cpu.h"
#include "renderer/volume/kernel_isas.h"
#include "renderer/volume/kernels.h"
#include "renderer/volume/occupancy.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/raycaster.h"
#include "renderer/volume/tf_table.h"
#include "renderer/volume/volume_accel.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

// Zero everywhere but a ball of radius r around c (values 0.6 inside, fading out).
std::shared_ptr<Volume> ball(std::array<int, 3> dims, std::array<double, 3> c, double r) {
  auto v = std::make_shared<Volume>();
  v->dims = dims;
  v->spacing = {1, 1, 1};
  v->values.assign(v->voxelCount(), 0.0f);
  for (int z = 0; z < dims[2]; ++z)
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x) {
        const double d = std::hypot(x - c[0], y - c[1], z - c[2]);
        v->values[v->index(x, y, z)] = (float)std::clamp(0.6 * (r - d) / 2, 0.0, 0.6);
      }
  return v;
}

// Transparent up to 0.05, like the default scene, so zero-valued blocks are empty.
std::shared_ptr<const Volume> generatedBall() { return ball({40, 40, 40}, {28, 12, 26}, 9); }

TransferFunction ballTf() {
  return TransferFunction({{0, 0, 0, 0, 0}, {0.05, 1, 0.5, 0.2, 0}, {0.2, 1, 0.5, 0.2, 0.3}, {1, 1, 1, 1, 0.9}});
}

TEST(NonEmptyBox, BoundsExactlyTheNonEmptyBlocks) {
  const auto v = ball({41, 33, 50}, {27, 9, 30}, 5);
  const MinMaxHierarchy h(*v);
  const TransferFunction tf = ballTf();
  const auto e = h.classify([&](float lo, float hi) { return tf.maxAlpha(lo, hi) == 0; });
  const auto d = h.dims(0);
  std::array<int, 3> lo = d, hi{0, 0, 0};
  for (int z = 0; z < d[2]; ++z)
    for (int y = 0; y < d[1]; ++y)
      for (int x = 0; x < d[0]; ++x)
        if (!e.empty[0][h.index(0, x, y, z)]) {
          const int b[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b[a]), hi[a] = std::max(hi[a], b[a] + 1);
        }
  ASSERT_FALSE(e.allEmpty());
  EXPECT_EQ(e.nonempty_lo, lo);
  EXPECT_EQ(e.nonempty_hi, hi);
  // The ball spans voxels ~20..34 in x: blocks 2..4 of 5, so the box is a real cut.
  EXPECT_GT(lo[0], 0);
  EXPECT_LT(hi[2], d[2]);
  const auto none = h.classify([](float, float) { return true; });
  EXPECT_TRUE(none.allEmpty());
}

TEST(NonEmptyBox, ClippedSpanKeepsTheGlobalGrid) {
  Volume v;
  v.dims = {16, 12, 20};
  v.values.assign(v.voxelCount(), 0.f);
  const VolumeGeometry g(v);
  const BrickBox brick{{2, 0, 3}, {16, 9, 20}}, clip{{5, 2, 3}, {11, 9, 14}};
  uint32_t seed = 5;
  auto rnd = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  int clipped_hits = 0;
  for (int i = 0; i < 3000; ++i) {
    // From anywhere around the volume towards a point inside it (world half extents <= 0.5).
    const Vec3 o{rnd() * 3 - 1.5, rnd() * 3 - 1.5, rnd() * 3 - 1.5}, p{rnd() - 0.5, rnd() - 0.5, rnd() - 0.5};
    const Ray r{o, normalize(p - o)};
    RaySpan full, c, only;
    int64_t before = -1, after = -1;
    const bool hit = raySpan(g, r, brick, 0.011, full);
    const bool chit = raySpanClipped(g, r, brick, clip, 0.011, c, &before, &after);
    const bool ohit = raySpan(g, r, clip, 0.011, only);
    const int64_t total = hit ? full.k_end - full.k_first : 0;
    ASSERT_EQ(chit, hit && ohit) << "ray " << i;
    if (!chit) {
      EXPECT_EQ(before + after, total) << "ray " << i;
      continue;
    }
    ++clipped_hits;
    // Same grid (t0, positions), samples = those of the brick that are also in the clip box.
    ASSERT_EQ(c.t0, full.t0);
    ASSERT_EQ(c.u0, full.u0);
    ASSERT_EQ(c.du, full.du);
    EXPECT_EQ(c.k_first, std::max(full.k_first, only.k_first)) << "ray " << i;
    EXPECT_EQ(c.k_end, std::min(full.k_end, only.k_end)) << "ray " << i;
    EXPECT_EQ(before, c.k_first - full.k_first);
    EXPECT_EQ(after, full.k_end - c.k_end);
    // Cut to ray parameters [t_lo, t_hi) too: exactly the clipped samples with t_k inside.
    const double t_lo = c.t0 + rnd() * 2, t_hi = t_lo + rnd() * 2;
    RaySpan d;
    int64_t d_before = -1, d_after = -1;
    const bool dhit = raySpanClipped(g, r, brick, clip, 0.011, d, &d_before, &d_after, t_lo, t_hi);
    int64_t lo = -1, hi = -1;
    for (int64_t k = c.k_first; k < c.k_end; ++k) {
      const double t = c.t0 + ((double)k + 0.5) * 0.011;
      if (t >= t_lo && t < t_hi) hi = k + 1, lo = lo < 0 ? k : lo;
    }
    ASSERT_EQ(dhit, lo >= 0) << "ray " << i;
    if (dhit) {
      EXPECT_EQ(d.k_first, lo) << "ray " << i;
      EXPECT_EQ(d.k_end, hi) << "ray " << i;
      EXPECT_EQ(d.u0, c.u0);
      EXPECT_EQ(d_before + (d.k_end - d.k_first) + d_after, total);
    } else {
      EXPECT_EQ(d_before + d_after, total);
    }
  }
  EXPECT_GT(clipped_hits, 500);  // the test exercised real clips
}

TEST(NonEmptyBox, SkippingOnAndOffGiveTheSameImageAndSampleTotal) {
  const std::shared_ptr<const Volume> vol = ball({40, 40, 40}, {28, 12, 26}, 6);
  const Raycaster rc(vol, ballTf());
  RenderOptions on = test::options("default", 2), off = test::options("default", 2);
  off.quality.skip_empty = false;
  for (const Brick& b : {wholeVolume(*vol), Brick{{20, 0, 0}, {40, 17, 40}}, Brick{{0, 26, 0}, {40, 40, 40}}})
    for (int frame : {0, 5, 11}) {
      const Camera cam = Orbit{16, {0.2, 1, 0.1}}.at(test::defaultCamera(), frame);
      RenderStats s_on, s_off;
      Rect a_on, a_off;
      const ImageF a = rc.render(cam, 60, 44, b, on, &s_on, &a_on);
      const ImageF c = rc.render(cam, 60, 44, b, off, &s_off, &a_off);
      EXPECT_TRUE(a == c) << "frame " << frame << " brick x " << b.lo[0] << ": clipping changed the image";
      EXPECT_EQ(a_on, a_off);
      EXPECT_EQ(s_on.samples + s_on.samples_skipped + s_on.samples_terminated,
                s_off.samples + s_off.samples_terminated)
          << "every grid sample is taken, skipped or terminated exactly once";
    }
  // A brick away from the ball is skipped whole.
  RenderStats st;
  const ImageF img = rc.render(test::defaultCamera(), 60, 44, Brick{{0, 26, 0}, {40, 40, 40}}, on, &st);
  EXPECT_EQ(st.samples, 0u);
  EXPECT_GT(st.samples_skipped, 1000u);
  EXPECT_TRUE(activeRegion(img).empty());
}

TEST(NonEmptyBox, DepthBoundsKeepImagesWithTheEyeAnywhere) {
  // Two balls at different depths; eyes outside, grazing, and inside the volume (rays
  // start at the eye, t0 = 0), whole volume and a brick: per-cell depth bounds must not
  // change a bit, and every grid sample stays accounted for.
  auto v = ball({48, 40, 44}, {12, 30, 10}, 6);
  const auto other = ball({48, 40, 44}, {36, 10, 34}, 5);
  for (size_t i = 0; i < v->values.size(); ++i) v->values[i] = std::max(v->values[i], other->values[i]);
  const std::shared_ptr<const Volume> vol = v;
  const Raycaster rc(vol, ballTf());
  RenderOptions on = test::options("default", 2), off = test::options("default", 2);
  off.quality.skip_empty = false;
  const Camera cams[] = {Camera{{0.3, 0.4, 2.0}, {0, 0, 0}, {0, 1, 0}, 35, false, 1},
                         Camera{{1.2, -0.1, 0.2}, {0, 0, 0}, {0, 1, 0}, 60, false, 1},
                         Camera{{0.05, 0.02, 0.0}, {0.4, 0.1, 0.3}, {0, 1, 0}, 90, false, 1},
                         Camera{{0.0, 0.0, 0.1}, {0.0, 0.2, -1}, {0, 1, 0}, 100, false, 1}};
  for (const Brick& b : {wholeVolume(*vol), Brick{{0, 0, 0}, {25, 40, 44}}})
    for (const Camera& cam : cams) {
      RenderStats s_on, s_off;
      const ImageF a = rc.render(cam, 57, 41, b, on, &s_on);
      const ImageF c = rc.render(cam, 57, 41, b, off, &s_off);
      EXPECT_TRUE(a == c) << "eye " << cam.eye[0] << "," << cam.eye[1] << "," << cam.eye[2] << " brick x " << b.hi[0];
      EXPECT_EQ(s_on.samples + s_on.samples_skipped + s_on.samples_terminated, s_off.samples + s_off.samples_terminated);
      EXPECT_LT(s_on.samples, s_off.samples);
    }
}

TEST(CastFastBatch, BitIdenticalToSingleRays) {
  // Rays of different lengths, some terminating early, with and without skipping: a batch of
  // three (one interleaved pair, one alone) must give exactly the colours and counts of three
  // separate casts.
  const auto vol = generatedBall();
  const VolumeAccel accel(*vol);
  const TransferFunction tf = ballTf();
  const auto emptiness = accel.hierarchy.classify([&](float lo, float hi) { return TfTable::rangeIsEmpty(tf, lo, hi); });
  const auto occupancy = cellOccupancy(accel, emptiness, tf);
  const TfTable table(tf, 1.0 / 40);
  const VolumeGeometry g(*vol);
  uint32_t seed = 9;
  auto rnd = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  int terminated_rays = 0;
  for (int i = 0; i < 400; ++i) {
    FastContext c{vol.get(), &accel, &table, &emptiness, i % 3 != 0, i % 2 ? 0.9f : 2.0f};
    c.occupancy = occupancy.data();
    RaySpan spans[3];
    int found = 0;
    while (found < 3) {
      const Vec3 o{rnd() * 3 - 1.5, rnd() * 3 - 1.5, 1.6}, p{0.1 * rnd() + 0.15, 0.1 * rnd() - 0.3, rnd() * 0.4 - 0.2};
      if (raySpan(g, Ray{o, normalize(p - o)}, wholeVolume(*vol), 1.0 / 40, spans[found])) ++found;
    }
    float single[3][4], batch[3][4];
    SampleCounts cs, cp;
    bool ts[3], tp[3];
    for (int r = 0; r < 3; ++r) ts[r] = castFast(c, spans[r], single[r], cs);
    float* outs[3] = {batch[0], batch[1], batch[2]};
    castFastBatch(c, spans, outs, 3, cp, tp);
    for (int r = 0; r < 3; ++r) {
      for (int ch = 0; ch < 4; ++ch) ASSERT_EQ(batch[r][ch], single[r][ch]) << "batch " << i << " ray " << r;
      ASSERT_EQ(tp[r], ts[r]);
      terminated_rays += ts[r];
    }
    ASSERT_EQ(cp.taken, cs.taken);
    ASSERT_EQ(cp.skipped, cs.skipped);
    ASSERT_EQ(cp.terminated, cs.terminated);
  }
  EXPECT_GT(terminated_rays, 20);  // early termination was exercised
}

TEST(CellOccupancy, EverySampleWithOpacityLiesInAnOccupiedCell) {
  // Random sample positions: a sample the table gives alpha > 0 must have its cell's bit set
  // (the kernel would pass over it otherwise), and the ball's rim must leave some cells of
  // non-empty blocks unset (else the kernel's test spares nothing).
  const auto vol = ball({41, 35, 44}, {20, 17, 22}, 11);
  const VolumeAccel accel(*vol);
  const TransferFunction tf = ballTf();
  const auto emptiness = accel.hierarchy.classify([&](float lo, float hi) { return TfTable::rangeIsEmpty(tf, lo, hi); });
  const auto occ = cellOccupancy(accel, emptiness, tf);
  ASSERT_EQ(occ.size(), (size_t)accel.nb[0] * accel.nb[1] * accel.nb[2] * kOccupancyWords);
  const TfTable table(tf, 1.0 / 40);
  uint32_t seed = 3;
  auto rnd = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  int lit = 0;
  for (int n = 0; n < 200000; ++n) {
    const double u[3] = {rnd() * 40, rnd() * 34, rnd() * 43};
    int i[3];
    for (int a = 0; a < 3; ++a) i[a] = std::min((int)u[a], vol->dims[a] - 2);
    float rgba[4];
    table.lookup((float)sampleTrilinear(*vol, u[0], u[1], u[2]), rgba);
    if (rgba[3] <= 0) continue;
    ++lit;
    const size_t b = (size_t)(i[0] / 8) + accel.nb[0] * ((size_t)(i[1] / 8) + accel.nb[1] * (size_t)(i[2] / 8));
    const int bit = cellBit(i[0], i[1], i[2]);
    ASSERT_TRUE((occ[b * kOccupancyWords + bit / 64] >> (bit % 64)) & 1)
        << "sample at " << u[0] << "," << u[1] << "," << u[2] << " has alpha " << rgba[3] << " in an empty cell";
  }
  EXPECT_GT(lit, 10000);
  int partial = 0, full = 0;
  for (size_t b = 0; b < occ.size() / kOccupancyWords; ++b) {
    int set = 0;
    for (int w = 0; w < kOccupancyWords; ++w) set += std::popcount(occ[b * kOccupancyWords + w]);
    if (emptiness.empty[0][b]) {
      EXPECT_EQ(set, 0) << "brick " << b << " is empty";
      continue;
    }
    (set == 64 * kOccupancyWords ? full : partial)++;
  }
  EXPECT_GT(partial, 10);
  EXPECT_GT(full, 0);
}

TEST(CellOccupancy, SkippingNeedsIt) {
  const auto vol = generatedBall();
  const VolumeAccel accel(*vol);
  const TransferFunction tf = ballTf();
  const auto emptiness = accel.hierarchy.classify([&](float lo, float hi) { return TfTable::rangeIsEmpty(tf, lo, hi); });
  const TfTable table(tf, 1.0 / 40);
  FastContext c{vol.get(), &accel, &table, &emptiness, true, 2.0f};
  RaySpan span;
  ASSERT_TRUE(raySpan(VolumeGeometry(*vol), Ray{{0, 0, 2}, {0, 0, -1}}, wholeVolume(*vol), 1.0 / 40, span));
  float out[4];
  SampleCounts counts;
  EXPECT_THROW(castFast(c, span, out, counts), std::invalid_argument);
}

TEST(CellOccupancy, EveryKernelPassesOverOnlyExactlyTransparentSamples) {
  // Values scattered around the transfer function's zero-opacity edge (0.05), where a cell
  // range a hair too tight would drop a sample that shows; random rays, each instruction set's
  // kernel with the cell test against the same kernel testing nothing (every bit set): the same
  // colours bit for bit, and the same samples ended by early termination.
  auto v = std::make_shared<Volume>();
  v->dims = {37, 29, 33};
  v->spacing = {1, 1, 1};
  v->values.assign(v->voxelCount(), 0.0f);
  uint32_t seed = 11;
  auto rnd = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  for (float& x : v->values) {
    const double r = rnd();
    x = r < 0.5 ? 0.0f : (float)(0.05 + (r - 0.75) * 0.004);  // half empty, half within 0.001 of the edge
  }
  for (int z = 20; z < 26; ++z)  // and a little solid matter for early termination
    for (int y = 10; y < 15; ++y)
      for (int x = 5; x < 30; ++x) v->values[v->index(x, y, z)] = 0.9f;
  const std::shared_ptr<const Volume> vol = v;
  const VolumeAccel accel(*vol);
  const TransferFunction tf = ballTf();
  const auto emptiness = accel.hierarchy.classify([&](float lo, float hi) { return TfTable::rangeIsEmpty(tf, lo, hi); });
  const auto occ = cellOccupancy(accel, emptiness, tf);
  const std::vector<uint64_t> all(occ.size(), ~uint64_t{0});
  int unset = 0;
  for (size_t b = 0; b < occ.size() / kOccupancyWords; ++b)
    if (!emptiness.empty[0][b])
      for (int w = 0; w < kOccupancyWords; ++w) unset += 64 - std::popcount(occ[b * kOccupancyWords + w]);
  ASSERT_GT(unset, 1000) << "the cell test would pass over nothing here";
  const TfTable table(tf, 1.0 / 40);
  const VolumeGeometry g(*vol);
  using CastFn = bool (*)(const FastContext&, const RaySpan&, float*, SampleCounts&);
  std::vector<std::pair<const char*, CastFn>> kernels{{"scalar", scalar::castFast}};
#if defined(__x86_64__)
  if (cpuIsa() >= Isa::Avx2) kernels.push_back({"avx2", avx2::castFast});
  if (cpuIsa() >= Isa::Avx512) kernels.push_back({"avx512", avx512::castFast});
#endif
  int lit = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 o{rnd() * 3 - 1.5, rnd() * 3 - 1.5, 1.6}, p{0.4 * rnd() - 0.2, 0.4 * rnd() - 0.2, rnd() * 0.4 - 0.2};
    RaySpan span;
    if (!raySpan(g, Ray{o, normalize(p - o)}, wholeVolume(*vol), 1.0 / 40, span)) continue;
    for (const auto& [name, cast] : kernels) {
      FastContext tested{vol.get(), &accel, &table, &emptiness, true, i % 2 ? 0.9f : 2.0f};
      FastContext untested = tested;
      tested.occupancy = occ.data();
      untested.occupancy = all.data();
      float a[4], b[4];
      SampleCounts ca, cb;
      const bool ta = cast(tested, span, a, ca), tb = cast(untested, span, b, cb);
      ASSERT_EQ(std::memcmp(a, b, sizeof a), 0) << name << " kernel, ray " << i << ": the cell test changed the colour";
      EXPECT_EQ(ta, tb) << name << " kernel, ray " << i;
      EXPECT_EQ(ca.terminated, cb.terminated) << name << " kernel, ray " << i;
      lit += a[3] > 0;
    }
  }
  EXPECT_GT(lit, 100);
}

}  // namespace
}  // namespace tessera::renderer
