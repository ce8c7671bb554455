// Shading in the fast kernel (see gradient.h): the gradient at a sample from the quantized
// gradient volume with the sample's own trilinear weights, then the same lighting as the
// reference path in float. Included by fast_kernel.cpp only, inside its per-ISA namespace, so
// each instruction set gets its own copy (no inline function shared across ISAs).
#pragma once

// Lights the premultiplied colour pc of a sample whose voxel-unit gradient is g.
inline void shadeFactors(const Consts& c, const float g[3], float& scale, float& add) {
  float diffuse = 1, highlight = 0;
  const float flat = (float)kFlatGradient;
  if (std::fabs(g[0]) >= flat || std::fabs(g[1]) >= flat || std::fabs(g[2]) >= flat) {
    float len2 = 0, nl = 0, nh = 0;
    for (int a = 0; a < 3; ++a) {
      const float gw = g[a] * c.inv_cell[a];
      len2 = std::fma(gw, gw, len2), nl = std::fma(gw, c.light[a], nl), nh = std::fma(gw, c.half[a], nh);
    }
    const float inv_len = 1.0f / std::sqrt(len2);
    diffuse = std::fabs(nl) * inv_len;
    if (c.ks > 0) {
      constexpr int last = HighlightTable::kEntries - 1;
      const float t = std::min(1.0f, std::fabs(nh) * inv_len) * (float)last;
      const int j = std::min((int)t, last - 1);
      highlight = std::fma(t - (float)j, c.highlight[j + 1] - c.highlight[j], c.highlight[j]);
    }
  }
  scale = std::fma(c.kd, diffuse, c.ka);  // colour * scale + highlight, premultiplied by alpha
  add = c.ks * highlight;
}

// Lower corner i and trilinear weights f of sample k: the same float operations as the
// packets' (u = u0 + k * du, one FMA, clamped), so a sample is where the classification saw it.
inline void samplePosition(const Consts& c, int64_t k, int i[3], float f[3]) {
  const float kf = (float)k;
  for (int a = 0; a < 3; ++a) {
    const float u = std::min(std::max(std::fma(kf, c.du[a], c.u0[a]), 0.0f), c.umax[a]);
    i[a] = std::min((int)u, c.imax[a]);
    f[a] = u - (float)i[a];
  }
}

// The trilinear gradient of sample k, in voxel units.
inline void gradientAt(const Consts& c, int64_t k, float g[3]) {
  float f[3];
  int i[3];
  samplePosition(c, k, i, f);
  const int16_t* p = c.grad + 4 * ((size_t)i[0] + (size_t)c.gdims[0] * ((size_t)i[1] + (size_t)c.gdims[1] * i[2]));
  const size_t sx = c.gstride[0], sy = c.gstride[1], sz = c.gstride[2];
#ifdef TESSERA_AVX2
  auto load = [](const int16_t* q) {
    return _mm_cvtepi32_ps(_mm_cvtepi16_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(q))));
  };
  auto lerp = [](__m128 a, __m128 b, float t) { return _mm_fmadd_ps(_mm_set1_ps(t), _mm_sub_ps(b, a), a); };
  auto lx = [&](const int16_t* q) { return lerp(load(q), load(q + sx), f[0]); };
  const __m128 v = lerp(lerp(lx(p), lx(p + sy), f[1]), lerp(lx(p + sz), lx(p + sy + sz), f[1]), f[2]);
  alignas(16) float out[4];
  _mm_store_ps(out, _mm_mul_ps(v, _mm_set1_ps(1.0f / GradientVolume::kScale)));
  for (int a = 0; a < 3; ++a) g[a] = out[a];
#else
  auto lerp = [](float a, float b, float t) { return std::fma(t, b - a, a); };
  for (int a = 0; a < 3; ++a) {
    auto lx = [&](const int16_t* q) { return lerp((float)q[a], (float)q[a + sx], f[0]); };
    const float v = lerp(lerp(lx(p), lx(p + sy), f[1]), lerp(lx(p + sz), lx(p + sy + sz), f[1]), f[2]);
    g[a] = v * (1.0f / GradientVolume::kScale);
  }
#endif
}

#ifdef TESSERA_AVX2
inline __m128 shadeSample(const Consts& c, int64_t k, __m128 pc) {
  if (_mm_cvtss_f32(_mm_shuffle_ps(pc, pc, 0xFF)) <= 0) return pc;  // nothing to light
  float g[3], scale, add;
  gradientAt(c, k, g);
  shadeFactors(c, g, scale, add);
  const __m128 a = _mm_shuffle_ps(pc, pc, 0xFF);
  const __m128 lit = _mm_min_ps(a, _mm_fmadd_ps(pc, _mm_set1_ps(scale), _mm_mul_ps(_mm_set1_ps(add), a)));
  return _mm_blend_ps(lit, pc, 8);  // alpha unchanged
}
#else
inline void shadeSample(const Consts& c, int64_t k, float pc[4]) {
  if (pc[3] <= 0) return;
  float g[3], scale, add;
  gradientAt(c, k, g);
  shadeFactors(c, g, scale, add);
  for (int ch = 0; ch < 3; ++ch) pc[ch] = std::min(pc[3], std::fma(pc[ch], scale, add * pc[3]));
}
#endif
