// Maximum intensity projection's ray kernels (scene `blend: maximum`, common/max_intensity.h):
// a ray's largest trilinear value, fast (the bricked 16-bit copy, bricks passed over whose
// largest voxel cannot raise the ray's maximum) and in double precision (the reference). The
// minimum projection (`blend: minimum`) is the same search over the values' complements.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/cpu.h"
#include "renderer/volume/kernels.h"

namespace tessera::renderer {

uint32_t quantizedUpperBound(float value) {
  // VolumeAccel rounds value * 65535 to nearest; one more keeps this above it whatever the
  // float rounding of the product.
  const double q = std::clamp((double)value, 0.0, 1.0) * VolumeAccel::kQuantScale;
  return std::min<uint32_t>(65535, (uint32_t)(q + 1.5));
}

namespace {

// The last sample of span from k on whose lower corner stays in the brick of i (k itself if
// none can be told): on each axis the ray moves along, the samples short of the next 8-voxel
// boundary by a margin far above the float rounding of the kernel's positions (positions are
// monotonic in k, and clamping only holds a sample in its border brick).
int64_t lastInBrick(const RaySpan& span, const int i[3], int64_t k) {
  int64_t last = span.k_end;
  for (int a = 0; a < 3; ++a) {
    const double du = span.du[a];
    if (du == 0) continue;
    const double edge = 8.0 * ((i[a] >> 3) + (du > 0 ? 1 : 0));
    const double margin = 1e-3 + 1e-6 * edge;
    const double t = (edge + (du > 0 ? -margin : margin) - span.u0[a]) / du;
    if (t < (double)last) last = (int64_t)std::floor(t);
  }
  return std::max(last, k);
}

}  // namespace

namespace {

// castMaximum for a maximum (kComplement false) or a minimum projection: a template, so that the
// per-sample loop does not ask which.
template <bool kComplement>
[[gnu::always_inline]] inline void castProjection(const FastContext& c, const RaySpan& span, float out[4],
                                                  SampleCounts& counts) {
  const MaxSkip& m = *c.maximum;
  if (m.floor_q > 65535u) {  // no value has opacity (a window over none): nothing shows, as the reference says
    out[0] = out[1] = out[2] = out[3] = 0;
    counts.skipped += (uint64_t)(span.k_end - span.k_first);
    return;
  }
  const Volume& v = *c.volume;
  const uint16_t* vol = c.accel->bricked.data();
  const int nb_x = c.accel->nb[0], nb_xy = c.accel->nb[0] * c.accel->nb[1];
  float u0[3], du[3], umax[3];
  int imax[3];
  for (int a = 0; a < 3; ++a) {
    u0[a] = (float)span.u0[a], du[a] = (float)span.du[a];
    umax[a] = (float)(v.dims[a] - 1), imax[a] = std::max(0, v.dims[a] - 2);
  }
  constexpr int kEdge = VolumeAccel::kEdge, oy = kEdge, oz = kEdge * kEdge;
  // Below the floor nothing shows (the floor's half a unit under it keeps values at it).
  float best = (float)m.floor_q - 0.5f;
  int64_t last_brick = -1, taken = 0, skipped = 0;
  bool pass = false;
  // One sample at a time: eight at once, their arithmetic in vector lanes and their corners read
  // lane by lane, was slower (scenes/mip.yaml 182 ms against 144-162, Intel Xeon, AVX-512).
  for (int64_t k = span.k_first; k < span.k_end; ++k) {
    const float kf = (float)k;
    int i[3];
    float f[3];
    for (int a = 0; a < 3; ++a) {
      const float u = std::min(std::max(u0[a] + kf * du[a], 0.0f), umax[a]);
      i[a] = std::min((int)u, imax[a]);
      f[a] = u - (float)i[a];
    }
    const int64_t brick = (i[0] >> 3) + (int64_t)nb_x * (i[1] >> 3) + (int64_t)nb_xy * (i[2] >> 3);
    // A trilinear value lies within its corners' range, so such a brick holds nothing larger.
    if (brick != last_brick) last_brick = brick, pass = c.skip && (float)m.brick_max[brick] <= best;
    if (pass) {
      // On to the brick's last sample, less one for rounding: stepping through such bricks
      // sample by sample, scenes/mip.yaml took 192 ms against 144-162 (Intel Xeon, AVX-512).
      const int64_t to = std::min(lastInBrick(span, i, k), span.k_end - 1);
      skipped += to - k + 1;
      k = to;
      continue;
    }
    ++taken;
    const uint16_t* p = vol + brick * VolumeAccel::kBrickSize + (i[0] & 7) + oy * (i[1] & 7) + oz * (i[2] & 7);
    auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
    const float x00 = lerp(p[0], p[1], f[0]), x10 = lerp(p[oy], p[oy + 1], f[0]);
    const float x01 = lerp(p[oz], p[oz + 1], f[0]), x11 = lerp(p[oy + oz], p[oy + oz + 1], f[0]);
    const float trilinear = lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2]);
    const float s = kComplement ? VolumeAccel::kQuantScale - trilinear : trilinear;
    if (s > best) {
      best = s;
      last_brick = -1;  // this brick may hold nothing larger now: the next sample asks again
      if (best >= (float)m.volume_max) {  // nothing further can be larger
        counts.terminated += (uint64_t)(span.k_end - k - 1);
        break;
      }
    }
  }
  counts.taken += (uint64_t)taken;
  counts.skipped += (uint64_t)skipped;
  const bool shows = best >= (float)m.floor_q;
  out[0] = shows ? best / VolumeAccel::kQuantScale : 0.0f;
  out[1] = out[2] = 0;
  out[3] = shows ? 1.0f : 0.0f;
}

}  // namespace

TESSERA_CLONES bool castMaximum(const FastContext& c, const RaySpan& span, float out[4], SampleCounts& counts) {
  if (c.maximum->complement) castProjection<true>(c, span, out, counts);
  else castProjection<false>(c, span, out, counts);
  return false;
}

void castReferenceMaximum(const Volume& v, double floor, bool complement, const RaySpan& span, double out[4],
                          SampleCounts& counts) {
  double best = -1;
  for (int64_t k = span.k_first; k < span.k_end; ++k) {
    const double kd = (double)k;
    const double s =
        sampleTrilinear(v, span.u0[0] + kd * span.du[0], span.u0[1] + kd * span.du[1], span.u0[2] + kd * span.du[2]);
    best = std::max(best, complement ? 1 - s : s);
  }
  counts.taken += (uint64_t)std::max<int64_t>(0, span.k_end - span.k_first);
  const bool shows = best >= floor;
  out[0] = shows ? best : 0;
  out[1] = out[2] = 0;
  out[3] = shows ? 1 : 0;
}

}  // namespace tessera::renderer
