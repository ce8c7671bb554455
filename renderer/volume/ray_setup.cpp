// Ray-box intervals and the global sample grid (see ray_setup.h).
#include "renderer/volume/ray_setup.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tessera::renderer {

VolumeGeometry::VolumeGeometry(const Volume& v) : origin(v.origin), whole(v.wholeDims()) {
  const Vec3 h = v.halfExtent();
  for (int a = 0; a < 3; ++a) {
    half[a] = h[a];
    cell[a] = 2.0 * h[a] / whole[a];
  }
}

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// A ray with its per-axis reciprocals computed once for all the boxes it is tested against.
struct PreparedRay {
  const Ray& r;
  double inv[3];
  explicit PreparedRay(const Ray& ray) : r(ray) {
    for (int a = 0; a < 3; ++a) inv[a] = r.dir[a] == 0 ? 0.0 : 1.0 / r.dir[a];
  }
};

// Inlined: called per ray, and out-of-line it kept t_in/t_out in memory.
[[gnu::always_inline]] inline bool interval(const VolumeGeometry& g, const PreparedRay& pr, const BrickBox& b, double& t_in, double& t_out) {
  t_in = -kInf;
  t_out = kInf;
  for (int a = 0; a < 3; ++a) {
    const double o = pr.r.origin[a], d = pr.r.dir[a];
    const double p_lo = g.plane(a, b.lo[a]), p_hi = g.plane(a, b.hi[a]);
    if (d == 0) {
      // Parallel to the slab: inside for all t or for none (half-open, like the t test).
      if (!(o >= p_lo && o < p_hi)) return false;
      continue;
    }
    // (p - o) * (1/d) is monotone in p under rounding, and every box uses the same 1/d,
    // so shared faces give identical parameters.
    const double t_lo = (p_lo - o) * pr.inv[a], t_hi = (p_hi - o) * pr.inv[a];
    t_in = std::max(t_in, d > 0 ? t_lo : t_hi);
    t_out = std::min(t_out, d > 0 ? t_hi : t_lo);
  }
  return t_in < t_out;
}

double sampleT(double t0, int64_t k, double step, double offset) { return t0 + ((double)k + offset) * step; }

// Smallest k >= 0 with t_k >= t (the same expression every brick evaluates). The guess
// may be off by one (inv_step is rounded); the two loops make the result exact.
[[gnu::always_inline]] inline int64_t firstAtOrAfter(double t0, double t, double step, double inv_step,
                                                     double offset) {
  double guess = std::ceil((t - t0) * inv_step - offset);
  int64_t k = guess > 0 ? (int64_t)guess : 0;
  while (k > 0 && sampleT(t0, k - 1, step, offset) >= t) --k;
  while (sampleT(t0, k, step, offset) < t) ++k;
  return k;
}
}  // namespace

bool boxInterval(const VolumeGeometry& g, const Ray& r, const BrickBox& b, double& t_in, double& t_out) {
  return interval(g, PreparedRay(r), b, t_in, t_out);
}

namespace {
// Whole-volume entry (t0) and the brick's ray parameters [b_in, b_out) within the volume;
// false if the ray misses the brick.
[[gnu::always_inline]] inline bool brickInterval(const VolumeGeometry& g, const PreparedRay& r, const BrickBox& brick,
                                                 RaySpan& span, double& b_in, double& b_out) {
  const BrickBox whole = g.wholeBox();
  double w_in, w_out;
  if (!interval(g, r, whole, w_in, w_out)) return false;
  if (!(w_out > 0)) return false;
  if (brick == whole) {
    b_in = w_in;
    b_out = w_out;
  } else if (!interval(g, r, brick, b_in, b_out)) {
    return false;
  }
  span.t0 = std::max(w_in, 0.0);
  b_in = std::max(b_in, span.t0);
  b_out = std::min(b_out, w_out);
  return b_in < b_out;
}

void samplePositions(const VolumeGeometry& g, const Ray& r, double step, RaySpan& span) {
  const double tb = span.t0 + span.offset * step;
  for (int a = 0; a < 3; ++a) {
    // In the whole volume's voxel coordinates, then moved to the held voxels' (exact: an
    // integer shift of a double well below 2^52).
    span.u0[a] = (r.origin[a] + tb * r.dir[a] + g.half[a]) / g.cell[a] - 0.5 - g.origin[a];
    span.du[a] = r.dir[a] * step / g.cell[a];
  }
}
}  // namespace

bool raySpanClipped(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, const BrickBox& clip, double step,
                    RaySpan& span, int64_t* before, int64_t* after, double t_lo, double t_hi, double offset) {
  if (before) *before = *after = 0;
  span.offset = offset;
  const PreparedRay pr(r);
  double b_in, b_out;
  if (!brickInterval(g, pr, brick, span, b_in, b_out)) return false;
  // One cut of the parameters, then one search per end: firstAtOrAfter is monotone in t, so
  // this is the brick's range cut to the clip's and to [t_lo, t_hi), with 2 searches, not 6.
  double c_in = std::max(b_in, t_lo), c_out = std::min(b_out, t_hi);
  if (clip != brick) {
    double i_in, i_out;
    if (!interval(g, pr, clip, i_in, i_out)) c_out = c_in;
    c_in = std::max(c_in, i_in), c_out = std::min(c_out, i_out);
  }
  const double inv_step = 1.0 / step;
  bool hit = c_in < c_out;
  if (hit) {
    span.k_first = firstAtOrAfter(span.t0, c_in, step, inv_step, offset);
    span.k_end = firstAtOrAfter(span.t0, c_out, step, inv_step, offset);
    hit = span.k_end > span.k_first;
  }
  if (before) {
    const int64_t k_first = firstAtOrAfter(span.t0, b_in, step, inv_step, offset),
                  k_end = firstAtOrAfter(span.t0, b_out, step, inv_step, offset);
    *before = hit ? span.k_first - k_first : std::max<int64_t>(0, k_end - k_first);
    *after = hit ? k_end - span.k_end : 0;
  }
  if (hit) samplePositions(g, r, step, span);
  return hit;
}

SpanRow::SpanRow(const RayGenerator& gen, const VolumeGeometry& g, const BrickBox& brick, const BrickBox& clip,
                 double grid_step, bool jittered)
    : basis(gen.basis()), brick_is_whole(brick == g.wholeBox()), clip_is_brick(clip == brick), jitter(jittered),
      step(grid_step), inv_step(1.0 / grid_step) {
  const BrickBox whole = g.wholeBox();
  for (int a = 0; a < 3; ++a) {
    half[a] = g.half[a];
    cell[a] = g.cell[a];
    origin[a] = g.origin[a];
    whole_lo[a] = g.plane(a, whole.lo[a]), whole_hi[a] = g.plane(a, whole.hi[a]);
    brick_lo[a] = g.plane(a, brick.lo[a]), brick_hi[a] = g.plane(a, brick.hi[a]);
    clip_lo[a] = g.plane(a, clip.lo[a]), clip_hi[a] = g.plane(a, clip.hi[a]);
  }
}

int64_t spanSamples(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, double step, double offset) {
  RaySpan span;
  double b_in, b_out;
  if (!brickInterval(g, PreparedRay(r), brick, span, b_in, b_out)) return 0;
  const double inv_step = 1.0 / step;
  return std::max<int64_t>(0, firstAtOrAfter(span.t0, b_out, step, inv_step, offset) -
                                  firstAtOrAfter(span.t0, b_in, step, inv_step, offset));
}

// One code path (one compiled copy of the grid arithmetic) for every span.
bool raySpan(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, double step, RaySpan& span, double offset) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  return raySpanClipped(g, r, brick, brick, step, span, nullptr, nullptr, -inf, inf, offset);
}

double pixelJitter(int px, int py) {
  // Interleaved gradient noise (Jimenez 2014): frac(52.9829189 * frac(0.06711056 x +
  // 0.00583715 y)), in 32-bit fractions: the inner sum wraps exactly, the outer product is
  // taken in 16.16 fixed point. Its neighbours differ more evenly than white noise's (no
  // grain) or R2's (a checker pattern at one pixel), as compared on the phantom's skin.
  const uint32_t inner = (uint32_t)px * 288237660u + (uint32_t)py * 25070368u;
  const uint32_t frac = (uint32_t)(((uint64_t)inner * 3472289u) >> 16);
  return (double)(frac >> 8) * 0x1p-24;  // the top 24 bits: exact in a double
}

void rowJitter(int px0, int py, double* offsets) {
  for (int i = 0; i < kSpanLanes; ++i) offsets[i] = pixelJitter(px0 + i, py);
}

Rect brickFootprint(const RayGenerator& gen, const VolumeGeometry& g, const BrickBox& b, int w, int h) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int c = 0; c < 8; ++c) {
    Vec3 p{g.plane(0, (c & 1) ? b.hi[0] : b.lo[0]), g.plane(1, (c & 2) ? b.hi[1] : b.lo[1]),
           g.plane(2, (c & 4) ? b.hi[2] : b.lo[2])};
    double sx, sy;
    if (!gen.project(p, sx, sy) || !std::isfinite(sx) || !std::isfinite(sy)) return Rect{0, 0, w, h};
    x0 = std::min(x0, sx), x1 = std::max(x1, sx), y0 = std::min(y0, sy), y1 = std::max(y1, sy);
  }
  const double lx = std::max(0.0, std::floor(x0) - 1), ly = std::max(0.0, std::floor(y0) - 1);
  const double hx = std::min((double)w, std::ceil(x1) + 1), hy = std::min((double)h, std::ceil(y1) + 1);
  if (!(lx < hx && ly < hy)) return Rect{};
  return Rect{(int)lx, (int)ly, (int)(hx - lx), (int)(hy - ly)};
}

}  // namespace tessera::renderer
