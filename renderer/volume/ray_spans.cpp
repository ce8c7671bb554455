// raySpans: raySpanClipped for kSpanLanes pixels of a row at once. Compiled once per
// instruction set like fast_kernel.cpp (TESSERA_KERNEL_ISA); every loop runs over the lanes
// with selects instead of branches, so the compiler vectorizes it. The arithmetic is
// raySpanClipped's, operation for operation (no contraction: -ffp-contract=off), and the
// selects spell out std::max/std::min (which keep the first argument on ties, -0.0 included),
// so every span is bit-identical (tests/renderer/ray_spans_test.cpp). A farm's renderer sets up
// a ray once per brick it crosses; one at a time that was 10-16% of its time.
#include <cmath>
#include <cstdint>
#include <limits>

#include "renderer/volume/ray_setup.h"

namespace tessera::renderer::TESSERA_KERNEL_ISA {

namespace {

constexpr int L = kSpanLanes;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Lanes {
  alignas(64) double o[3][L], d[3][L], inv[3][L];
};

// The pixel rays (RayGenerator::ray) and their reciprocals (PreparedRay).
void makeRays(const RayGenerator::Basis& b, int px0, int py, Lanes& r) {
  const double cy = py + 0.5;
  const double y = (1.0 - 2.0 * cy / b.height) * b.tan_half;
  alignas(64) double x[L];
  for (int i = 0; i < L; ++i) x[i] = (2.0 * ((px0 + i) + 0.5) / b.width - 1.0) * b.aspect * b.tan_half;
  // One loop per component: a loop over the lanes alone is what the vectorizer takes.
  double* const out = b.orthographic ? &r.o[0][0] : &r.d[0][0];
  const Vec3 base = b.orthographic ? b.eye : b.fwd, along = b.orthographic ? b.fwd : b.eye;
  for (int a = 0; a < 3; ++a) {
    const double c = base[a], rx = b.right[a], uy = b.up[a] * y, keep = along[a];
    double* dst = out + a * L;
    double* other = (b.orthographic ? &r.d[0][0] : &r.o[0][0]) + a * L;
    for (int i = 0; i < L; ++i) dst[i] = c + rx * x[i] + uy, other[i] = keep;
  }
  if (!b.orthographic) {
    double* dx = r.d[0];
    double* dy = r.d[1];
    double* dz = r.d[2];
    for (int i = 0; i < L; ++i) {
      const double s = 1.0 / std::sqrt(dx[i] * dx[i] + dy[i] * dy[i] + dz[i] * dz[i]);
      dx[i] *= s, dy[i] *= s, dz[i] *= s;
    }
  }
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < L; ++i) r.inv[a][i] = r.d[a][i] == 0 ? 0.0 : 1.0 / r.d[a][i];
}

// interval() of ray_setup.cpp on every lane; ok[i] &= the interval is not empty. A ray
// parallel to a slab and outside it misses; a missed box's t values are not used. Masks
// are 64-bit and combined with & (not &&), so the loops have no branches to vectorize around.
[[gnu::always_inline]] inline void interval(const Lanes& r, const double lo[3], const double hi[3], double* t_in,
                                            double* t_out, int64_t* ok) {
  for (int i = 0; i < L; ++i) t_in[i] = -kInf, t_out[i] = kInf;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < L; ++i) {
      const double o = r.o[a][i], d = r.d[a][i];
      const double t_lo = (lo[a] - o) * r.inv[a][i], t_hi = (hi[a] - o) * r.inv[a][i];
      const double enter = d > 0 ? t_lo : t_hi, leave = d > 0 ? t_hi : t_lo;
      const int64_t slab = d != 0;
      ok[i] &= slab | ((int64_t)(o >= lo[a]) & (int64_t)(o < hi[a]));
      t_in[i] = (slab & (int64_t)(t_in[i] < enter)) ? enter : t_in[i];
      t_out[i] = (slab & (int64_t)(leave < t_out[i])) ? leave : t_out[i];
    }
  for (int i = 0; i < L; ++i) ok[i] &= (int64_t)(t_in[i] < t_out[i]);
}

// ray_setup.cpp's sampleT and firstAtOrAfter's loops, repeated here on purpose: this file is
// compiled once per instruction set, and every copy must keep its code to itself
// (tests/renderer/kernel_symbols.cmake).
double sampleT(double t0, int64_t k, double step, double offset) { return t0 + ((double)k + offset) * step; }

// firstAtOrAfter's correction of its guess (rarely more than one step).
int64_t settle(int64_t k, double t0, double t, double step, double offset) {
  while (k > 0 && sampleT(t0, k - 1, step, offset) >= t) --k;
  while (sampleT(t0, k, step, offset) < t) ++k;
  return k;
}

// Jitter as a template argument: mid-step, the offsets are the constant 0.5 the compiler folds
// (the default frame's set-up as fast as before jitter existed).
template <bool Jitter>
unsigned spansOf(const SpanRow& row, int px0, int py, int n, const double* t_lo, const double* t_hi, RaySpan* spans) {
  Lanes r;
  makeRays(row.basis, px0, py, r);
  alignas(64) double w_in[L], w_out[L], b_in[L], b_out[L], c_in[L], c_out[L], t0[L], g_in[L], g_out[L], off[L];
  alignas(64) int64_t ok[L];
  if constexpr (Jitter) rowJitter(px0, py, off);  // out of line: shared by every instruction set's copy
  const auto offset = [&](int i) {
    if constexpr (Jitter) return off[i];
    else return 0.5;
  };
  for (int i = 0; i < L; ++i) ok[i] = i < n;
  // brickInterval: the whole volume's entry starts the grid; the brick's part of it.
  interval(r, row.whole_lo, row.whole_hi, w_in, w_out, ok);
  for (int i = 0; i < L; ++i) ok[i] &= (int64_t)(w_out[i] > 0);
  if (row.brick_is_whole) {
    for (int i = 0; i < L; ++i) b_in[i] = w_in[i], b_out[i] = w_out[i];
  } else {
    interval(r, row.brick_lo, row.brick_hi, b_in, b_out, ok);
  }
  for (int i = 0; i < L; ++i) {
    t0[i] = w_in[i] < 0.0 ? 0.0 : w_in[i];
    b_in[i] = b_in[i] < t0[i] ? t0[i] : b_in[i];
    b_out[i] = w_out[i] < b_out[i] ? w_out[i] : b_out[i];
    ok[i] &= (int64_t)(b_in[i] < b_out[i]);
    // raySpanClipped: the brick's range cut to [t_lo, t_hi) and to the clip box.
    c_in[i] = b_in[i] < t_lo[i] ? t_lo[i] : b_in[i];
    c_out[i] = t_hi[i] < b_out[i] ? t_hi[i] : b_out[i];
  }
  if (!row.clip_is_brick) {
    alignas(64) double i_in[L], i_out[L];
    interval(r, row.clip_lo, row.clip_hi, i_in, i_out, ok);
    for (int i = 0; i < L; ++i) {
      c_in[i] = c_in[i] < i_in[i] ? i_in[i] : c_in[i];
      c_out[i] = i_out[i] < c_out[i] ? i_out[i] : c_out[i];
    }
  }
  // firstAtOrAfter's guesses for both ends.
  for (int i = 0; i < L; ++i) {
    ok[i] &= (int64_t)(c_in[i] < c_out[i]);
    g_in[i] = std::ceil((c_in[i] - t0[i]) * row.inv_step - offset(i));
    g_out[i] = std::ceil((c_out[i] - t0[i]) * row.inv_step - offset(i));
  }
  unsigned hits = 0;
  for (int i = 0; i < n; ++i) {
    if (!ok[i]) continue;
    RaySpan& s = spans[i];
    s.t0 = t0[i];
    s.offset = offset(i);
    s.k_first = settle(g_in[i] > 0 ? (int64_t)g_in[i] : 0, t0[i], c_in[i], row.step, offset(i));
    s.k_end = settle(g_out[i] > 0 ? (int64_t)g_out[i] : 0, t0[i], c_out[i], row.step, offset(i));
    if (s.k_end <= s.k_first) continue;
    // samplePositions
    const double tb = s.t0 + offset(i) * row.step;
    for (int a = 0; a < 3; ++a) {
      s.u0[a] = (r.o[a][i] + tb * r.d[a][i] + row.half[a]) / row.cell[a] - 0.5 - row.origin[a];
      s.du[a] = r.d[a][i] * row.step / row.cell[a];
    }
    hits |= 1u << i;
  }
  return hits;
}

}  // namespace

unsigned raySpans(const SpanRow& row, int px0, int py, int n, const double* t_lo, const double* t_hi, RaySpan* spans) {
  return row.jitter ? spansOf<true>(row, px0, py, n, t_lo, t_hi, spans) : spansOf<false>(row, px0, py, n, t_lo, t_hi, spans);
}

}  // namespace tessera::renderer::TESSERA_KERNEL_ISA
