// Fast kernel: float, SIMD over 8 consecutive samples of one ray (AVX2 arithmetic, voxels read lane by lane), table
// classification, empty-space skipping over the min-max hierarchy, early termination.
// Compiled once per instruction set (TESSERA_KERNEL_ISA = scalar | avx2 | avx512, each its
// own namespace); kernel_dispatch.cpp calls the one the CPU supports.
// Every sample's value depends only on its index k (position u0 + k*du, one FMA), never on
// how samples were grouped or skipped, so skipping cannot change a single bit.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include "common/cpu.h"
#include "renderer/volume/kernels.h"
#include "renderer/volume/leaper.h"

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define TESSERA_AVX2 1
#endif

namespace tessera::renderer::TESSERA_KERNEL_ISA {

namespace {

using fast::Leaper;
using fast::kInf;
using fast::kMinRun;
constexpr int kLanes = 8;
// Float sample indices are exact below 2^24.
constexpr int64_t kMaxSamples = int64_t{1} << 24;

// Samples [begin, end) of a ray to be taken.
struct Run {
  int64_t begin, end;
  uint64_t skipped_before_end;  // batch skip count when this run was last extended
};

struct Consts {
  float u0[3], du[3], umax[3];
  int imax[3];
  int nb_x, nb_xy;         // bricks per row / per slice
  const uint16_t* vol;     // bricked (VolumeAccel); a 32-bit read at i holds voxels i and i+1
  const uint64_t* occ;     // cellOccupancy, while skipping (null: no cell test)
  const float* rgba;
  const int32_t* nonzero;
  int first_nz, last_nz;  // TfTable::firstNonzero/lastNonzero
  float to_table, table_offset;
  bool gather;             // read voxels (and gradients) by gather instructions (cpuGathers)
  // Shading (fast_shade.h); grad == nullptr: unlit.
  const int16_t* grad;
  int gdims[2];           // held voxels per row / per column
  int gstride[3];         // int16s to the next voxel on each axis (0 on a one-voxel axis)
  float ka, kd, ks;
  const float* highlight;  // HighlightTable
  float inv_cell[3], light[3], half[3];
};

// A ray's colour and alpha so far (premultiplied) and its transmittance, the product of
// (1 - alpha) over its samples. Kept apart from the alpha, each sample adds one fused
// multiply-add to the colour's chain and one to the transmittance's; the transmittance's chain
// does not wait for the colour's (compositing as c += (1 - c.a) * s chained a shuffle, a
// subtract and the FMA per sample).
struct Accum {
#ifdef TESSERA_AVX2
  __m128 c = _mm_setzero_ps(), t = _mm_set1_ps(1.0f);
#else
  float c[4] = {0, 0, 0, 0}, t = 1.0f;
#endif
};


#include "renderer/volume/fast_shade.h"
#include "renderer/volume/fast_packets.h"

// The constants every ray of a frame shares (the ray's own are set by RayState).
Consts frameConsts(const FastContext& ctx) {
  const Volume& v = *ctx.volume;
  Consts c{};
  for (int a = 0; a < 3; ++a) {
    c.umax[a] = (float)(v.dims[a] - 1);
    c.imax[a] = std::max(0, v.dims[a] - 2);
  }
  c.nb_x = ctx.accel->nb[0];
  c.nb_xy = ctx.accel->nb[0] * ctx.accel->nb[1];
  c.vol = ctx.accel->bricked.data();
  c.occ = nullptr;  // per ray: only while skipping
  c.rgba = ctx.table->rgba();
  c.nonzero = ctx.table->nonzero();
  // Table position of a scalar in quantized units [0, 65535]: s * to_table + table_offset.
  c.to_table = ctx.table->scale() / VolumeAccel::kQuantScale;
  c.table_offset = ctx.table->offset();
  c.first_nz = ctx.table->firstNonzero();
  c.last_nz = ctx.table->lastNonzero();
  c.gather = cpuGathers() == Gathers::Hardware;
  c.grad = nullptr;
  if (!ctx.shade) return c;
  const ShadeParams& p = *ctx.shade;
  c.grad = ctx.gradients->q.data();
  c.gdims[0] = v.dims[0], c.gdims[1] = v.dims[1];
  c.gstride[0] = v.dims[0] > 1 ? 4 : 0;
  c.gstride[1] = v.dims[1] > 1 ? 4 * v.dims[0] : 0;
  c.gstride[2] = v.dims[2] > 1 ? 4 * v.dims[0] * v.dims[1] : 0;
  c.ka = (float)p.ambient, c.kd = (float)p.diffuse, c.ks = (float)p.specular;
  for (int a = 0; a < 3; ++a) c.inv_cell[a] = (float)(1 / p.cell[a]);
  c.highlight = ctx.highlight->values.data();
  return c;
}

// One ray in flight: its constants, leaper, position and the runs of the current batch.
// Two phases per batch: the leaper (branchy, scalar) lists the runs to sample, then the
// packets run over that list; keeping them apart lets each loop stay tight and predictable.
struct RayState {
  static constexpr int kBatch = 16;
  Consts c;
  bool skip = false;
  Leaper leaper;
  int64_t k = 0, k_end = 0;
  bool terminated = false;
  Accum acc;
  // Samples planned ahead of sampling, at most: an opaque ray ends a few samples into its
  // first non-empty block, and planning the rest of it (the leaper walked on through the
  // non-empty blocks, merging them into one run) was wasted.
  // 32 against 64: opaque Marschner-Lobb 3% faster, the hollow shell 1% slower; against
  // 128: 7% and 2%; growing it with every batch gained nothing (AMD EPYC, AVX-512, 2 threads).
  static constexpr int64_t kPlanAhead = 32;
  Run runs[kBatch];
  int n = 0;
  int64_t planned = 0;  // samples in the batch's runs
  uint64_t batch_skipped = 0;

  // `base`: frameConsts(ctx), set up once for many rays.
  // `lights` (shading only): the ray's light and halfway directions at index li.
  // Inlined by force: the per-ray set-up and the leaper's decision are a large share of an
  // opaque frame, and GCC's inlining budget dropped them out of line once the kernel had
  // more variants (3.5% slower, shaded Marschner-Lobb).
  [[gnu::always_inline]] RayState(const FastContext& ctx, const Consts& base, const RaySpan& span,
                                  const LightBlock* lights, int li)
      : c(base) {
    if (span.k_end >= kMaxSamples)
      throw std::invalid_argument("castFast: more than 2^24 samples on one ray (step too small)");
    for (int a = 0; a < 3; ++a) {
      c.u0[a] = (float)span.u0[a];
      c.du[a] = (float)span.du[a];
    }
    if (lights)
      for (int a = 0; a < 3; ++a) c.light[a] = lights->l[li][a], c.half[a] = lights->h[li][a];
    skip = ctx.skip && ctx.emptiness;
    if (skip) {
      leaper = Leaper(span, *ctx.volume, ctx.accel->hierarchy, *ctx.emptiness);
      c.occ = ctx.occupancy;
    }
    k = span.k_first;
    k_end = span.k_end;
  }

  bool active() const { return k < k_end; }
  bool planning() const { return k < k_end && n < kBatch && planned < kPlanAhead; }

  // One leaper decision: leaps over empty samples or appends a run.
  [[gnu::always_inline]] void plan() {
    if (!skip) {
      runs[n++] = Run{k, k_end, 0};
      k = k_end;
      return;
    }
    int64_t run_end = k_end;
    const int64_t next = leaper.step(k, k_end, run_end);
    if (next > k) {
      batch_skipped += (uint64_t)(next - k);
      k = next;
      return;
    }
    // Whole packets up to the block exit, at least kMinRun samples: extra samples are
    // harmless (just not skipped, or passed over by the cell test) and cheaper than another
    // leaper decision (see kMinRun).
    run_end = std::min(k_end, k + (std::max<int64_t>(kMinRun, run_end - k) + kLanes - 1) / kLanes * kLanes);
    if (n > 0 && runs[n - 1].end == k) {
      runs[n - 1].end = run_end;
      runs[n - 1].skipped_before_end = batch_skipped;
    } else {
      runs[n++] = Run{k, run_end, batch_skipped};
    }
    planned += run_end - k;
    k = run_end;
  }

  // Samples the batch's runs and starts the next batch.
  void sample(float et, SampleCounts& counts) {
    counts.skipped += batch_skipped;
    for (int r = 0; r < n; ++r) {
      bool done = false;
#ifdef TESSERA_AVX2
      int64_t j;
      const int64_t b = runs[r].begin, e = runs[r].end;
      // Skipping: packets are tested against the cells first (c.occ); without: the early
      // out for an all-empty packet (see classifyPacket).
      if (c.occ)
        done = c.grad ? runPackets<false, true, true>(c, b, e, et, acc, j) : runPackets<false, true, false>(c, b, e, et, acc, j);
      else
        done = c.grad ? runPackets<true, false, true>(c, b, e, et, acc, j) : runPackets<true, false, false>(c, b, e, et, acc, j);
      counts.taken += (uint64_t)(j - runs[r].begin);
#else
      int64_t j = runs[r].begin;
      while (j < runs[r].end && !done) {
        const int used = packet(c, j, (int)std::min<int64_t>(kLanes, runs[r].end - j), et, acc, done);
        counts.taken += (uint64_t)used;
        j += used;
      }
#endif
      if (done) {
        // Everything after j counts as terminated, including what the leaper had passed over.
        counts.skipped -= batch_skipped - runs[r].skipped_before_end;
        counts.terminated += (uint64_t)(k_end - j);
        k = k_end;
        terminated = true;
        break;
      }
    }
    n = 0;
    planned = 0;
    batch_skipped = 0;
  }

  void store(float out[4]) const {
#ifdef TESSERA_AVX2
    _mm_storeu_ps(out, acc.c);
#else
    for (int i = 0; i < 4; ++i) out[i] = acc.c[i];
#endif
  }
};

}  // namespace

namespace {

bool castOne(const FastContext& ctx, const Consts& base, const RaySpan& span, const LightBlock* lights, int li,
             float out[4], SampleCounts& counts) {
  RayState s(ctx, base, span, lights, li);
  while (s.active()) {
    while (s.planning()) s.plan();
    s.sample(ctx.early_termination, counts);
  }
  s.store(out);
  return s.terminated;
}

[[gnu::always_inline]] inline void castPair(const FastContext& ctx, const Consts& base, const RaySpan* spans,
                                            const LightBlock* lights, int li, float* const* out, SampleCounts& counts,
                                            bool* terminated) {
  RayState a(ctx, base, spans[0], lights, li), b(ctx, base, spans[1], lights, li + 1);
  while (a.active() || b.active()) {
    // The two rays' decisions are independent chains: interleaved, they overlap.
    for (;;) {
      const bool pa = a.planning(), pb = b.planning();
      if (!(pa | pb)) break;
      if (pa) a.plan();
      if (pb) b.plan();
    }
    a.sample(ctx.early_termination, counts);
    b.sample(ctx.early_termination, counts);
  }
  a.store(out[0]);
  b.store(out[1]);
  terminated[0] = a.terminated;
  terminated[1] = b.terminated;
}

}  // namespace

namespace {
void checkContext(const FastContext& ctx) {
  if (ctx.skip && ctx.emptiness && !ctx.occupancy)
    throw std::invalid_argument("castFast: skipping needs the cell occupancy of the emptiness");
}
}  // namespace

bool castFast(const FastContext& ctx, const RaySpan& span, float out[4], SampleCounts& counts) {
  checkContext(ctx);
  LightBlock lights;
  if (ctx.shade) rayLights(*ctx.shade, &span, 1, lights);
  return castOne(ctx, frameConsts(ctx), span, ctx.shade ? &lights : nullptr, 0, out, counts);
}

void castFastBatch(const FastContext& ctx, const RaySpan* spans, float* const* out, int n, SampleCounts& counts,
                   bool* terminated) {
  checkContext(ctx);
  const Consts base = frameConsts(ctx);
  LightBlock lights;
  for (int b = 0; b < n; b += kLightBlock) {
    const int m = std::min(kLightBlock, n - b);
    if (ctx.shade) rayLights(*ctx.shade, spans + b, m, lights);
    const LightBlock* lb = ctx.shade ? &lights : nullptr;
    int i = 0;
    for (; i + 1 < m; i += 2) castPair(ctx, base, spans + b + i, lb, i, out + b + i, counts, terminated + b + i);
    if (i < m) terminated[b + i] = castOne(ctx, base, spans[b + i], lb, i, out[b + i], counts);
  }
}

}  // namespace tessera::renderer::TESSERA_KERNEL_ISA
