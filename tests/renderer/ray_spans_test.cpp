// raySpans (several rays at once, per instruction set) against raySpanClipped one ray at a
// time: the same spans bit for bit, for every instruction set this CPU has.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "common/cpu.h"
#include "renderer/volume/kernel_isas.h"
#include "renderer/volume/ray_setup.h"

namespace tessera::renderer {
namespace {

using SpansFn = unsigned (*)(const SpanRow&, int, int, int, const double*, const double*, RaySpan*);

std::vector<std::pair<const char*, SpansFn>> available() {
  std::vector<std::pair<const char*, SpansFn>> v{{"scalar", scalar::raySpans}};
#if defined(__x86_64__)
  if (cpuIsa() >= Isa::Avx2) v.push_back({"avx2", avx2::raySpans});
  if (cpuIsa() >= Isa::Avx512) v.push_back({"avx512", avx512::raySpans});
#endif
  return v;
}

bool same(const RaySpan& a, const RaySpan& b) {
  return std::memcmp(&a.t0, &b.t0, sizeof a.t0) == 0 && std::memcmp(&a.offset, &b.offset, sizeof a.offset) == 0 &&
         a.k_first == b.k_first && a.k_end == b.k_end &&
         std::memcmp(a.u0.data(), b.u0.data(), sizeof a.u0) == 0 && std::memcmp(a.du.data(), b.du.data(), sizeof a.du) == 0;
}

// A volume window (held voxels from `origin` in a whole volume of `whole`), spacing anisotropic.
Volume window(std::array<int, 3> whole, std::array<int, 3> origin, std::array<int, 3> dims) {
  Volume v;
  v.dims = dims;
  v.origin = origin;
  v.whole_dims = whole;
  v.spacing = {1.0, 0.8, 1.3};
  return v;
}

// Every pixel of a w x h image through raySpans and through raySpanClipped.
int compareAll(SpansFn fn, const char* isa, const Camera& cam, int w, int h, const Volume& v, const BrickBox& brick,
               const BrickBox& clip, double step, bool depth_cut, bool jitter) {
  const RayGenerator gen(cam, w, h);
  const VolumeGeometry g(v);
  const SpanRow row(gen, g, brick, clip, step, jitter);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int hits = 0;
  for (int py = 0; py < h; ++py)
    for (int px0 = 0; px0 < w; px0 += kSpanLanes) {
      const int n = std::min(kSpanLanes, w - px0);
      double lo[kSpanLanes], hi[kSpanLanes];
      for (int i = 0; i < kSpanLanes; ++i) {
        // Depth cuts that fall inside, before and after the volume.
        lo[i] = depth_cut ? 0.5 * ((px0 + i + py) % 7) : -kInf;
        hi[i] = depth_cut ? lo[i] + 0.3 + 0.2 * ((px0 + i) % 5) : kInf;
      }
      RaySpan spans[kSpanLanes];
      const unsigned got = fn(row, px0, py, n, lo, hi, spans);
      EXPECT_EQ(got >> n, 0u) << isa << ": a hit beyond the n pixels asked";
      for (int i = 0; i < n; ++i) {
        RaySpan want;
        const double offset = jitter ? pixelJitter(px0 + i, py) : 0.5;
        const bool hit =
            raySpanClipped(g, gen.pixelRay(px0 + i, py), brick, clip, step, want, nullptr, nullptr, lo[i], hi[i], offset);
        if (hit != (((got >> i) & 1) != 0) || (hit && !same(want, spans[i]))) {
          ADD_FAILURE() << isa << ": pixel " << px0 + i << "," << py << (hit ? " differs" : " hit on one side only");
          return hits;  // one report per image
        }
        hits += hit;
      }
    }
  return hits;
}

TEST(RaySpans, BitIdenticalToOneRayAtATime) {
  const Volume v = window({40, 30, 20}, {10, 0, 5}, {20, 30, 10});
  const BrickBox whole{{-10, 0, -5}, {30, 30, 15}};
  const BrickBox brick{{0, 0, 0}, {20, 30, 10}};
  const BrickBox clip{{3, 4, 1}, {17, 25, 9}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (auto [name, fn] : available()) {
    int hits = 0;
    for (int c = 0; c < 12; ++c) {
      Camera cam;
      cam.eye = {2.5 * u(rng), 2.5 * u(rng), 2.5 * u(rng)};
      if (c == 0) cam.eye = {0, 0, 2.5};                  // axis-aligned: rays parallel to slabs
      if (c == 1) cam.eye = {0.1, 0.05, 0.2};             // inside the volume
      cam.orthographic = c % 3 == 2;
      cam.height = 1.2;
      const int w = 37 + c, h = 23 + c;                   // rows that do not fill the lanes
      const bool jitter = c % 4 >= 2;  // quality.jitter: each pixel's own offset on both sides
      hits += compareAll(fn, name, cam, w, h, v, brick, brick, 1.0 / 64, false, jitter);
      hits += compareAll(fn, name, cam, w, h, v, brick, clip, 1.0 / 100, c % 2 == 0, jitter);
      hits += compareAll(fn, name, cam, w, h, v, whole, whole, 1.0 / 256, c % 2 == 1, !jitter);
    }
    EXPECT_GT(hits, 5000) << name << ": the cases must hit";
  }
}

// The jitter offsets: in [0, 1), spread evenly over the step, and different from one pixel to
// the next (rings become noise only if neighbours sample at different depths).
TEST(RaySpans, PixelJitterSpreadsNeighboursOverTheStep) {
  int bins[8] = {};
  int equal_neighbours = 0;
  for (int py = 0; py < 64; ++py)
    for (int px = 0; px < 64; ++px) {
      const double j = pixelJitter(px, py);
      ASSERT_GE(j, 0.0);
      ASSERT_LT(j, 1.0);
      ++bins[(int)(j * 8)];
      equal_neighbours += std::abs(j - pixelJitter(px + 1, py)) < 1.0 / 16;
      equal_neighbours += std::abs(j - pixelJitter(px, py + 1)) < 1.0 / 16;
    }
  for (int b = 0; b < 8; ++b) EXPECT_NEAR(bins[b], 512, 20) << "bin " << b;  // 64^2 / 8
  EXPECT_EQ(equal_neighbours, 0) << "neighbouring pixels within 1/16 of a step of each other";
  // Pinned bits: every process and build must compute the same offsets (the farm's contract).
  EXPECT_EQ(pixelJitter(0, 0), 0.0);
  EXPECT_EQ(pixelJitter(1, 0), 9323330 * 0x1p-24);
  EXPECT_EQ(pixelJitter(0, 1), 5188677 * 0x1p-24);
  EXPECT_EQ(pixelJitter(3, 5), 3581730 * 0x1p-24);
}

}  // namespace
}  // namespace tessera::renderer
