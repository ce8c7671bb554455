// Shading in the fast kernel (see gradient.h): the gradient at a sample from the quantized
// gradient volume with the sample's own trilinear weights, then the same lighting as the
// reference path in float. Included by fast_kernel.cpp only, inside its per-ISA namespace, so
// each instruction set gets its own copy (no inline function shared across ISAs).
#pragma once

// rayLight (gradient.cpp) for up to kLightBlock rays at once, in lane loops the compiler
// vectorizes: the same operations, so the same values; one ray at a time, its square roots and
// divisions were ~2.5% of a shaded frame.
constexpr int kLightBlock = 32;
struct LightBlock {
  float l[kLightBlock][3], h[kLightBlock][3];
};

void normalizeLanes(double (&v)[3][kLightBlock], int n) {
  for (int i = 0; i < n; ++i) {
    const double len = std::sqrt(v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
    v[0][i] = len > 0 ? v[0][i] / len : 0;
    v[1][i] = len > 0 ? v[1][i] / len : 0;
    v[2][i] = len > 0 ? v[2][i] / len : 0;
  }
}

void rayLights(const ShadeParams& p, const RaySpan* spans, int n, LightBlock& out) {
  alignas(64) double e[3][kLightBlock], h[3][kLightBlock];  // towards the eye; halfway
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) e[a][i] = -spans[i].du[a] * p.cell[a];
  normalizeLanes(e, n);
  const bool headlight = p.light[0] == 0 && p.light[1] == 0 && p.light[2] == 0;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) {
      const double l = headlight ? e[a][i] : p.light[a];
      out.l[i][a] = (float)l;
      h[a][i] = l + e[a][i];
    }
  normalizeLanes(h, n);
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) out.h[i][a] = (float)h[a][i];
}

#ifdef TESSERA_AVX2
// Eight samples at once, lanes holding samples (indices kf) with premultiplied colours
// r, g, b and alpha a: shadeSample's operations lane by lane, so every lane's result is
// shadeSample's to the bit (tests/integration/simd_paths_test.cpp compares the kernels).
// Per sample, one at a time, the gradient's loads and the lighting's square root, division and
// branches were ~60% of a shaded opaque frame.
// Not inlined: its size pushed the leaper's planning out of the callers' inlining (unlit frames 5% slower).
[[gnu::noinline]] void shadePacket(const Consts& c, __m256 kf, __m256 rgba[4]) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 a = rgba[3];
  const __m256 lit_lanes = _mm256_cmp_ps(a, zero, _CMP_NLE_UQ);  // !(alpha <= 0), as shadeSample
  if (_mm256_movemask_ps(lit_lanes) == 0) return;
  // samplePosition
  __m256 f[3];
  alignas(32) int32_t ii[3][8];
  for (int ax = 0; ax < 3; ++ax) {
    __m256 u = _mm256_fmadd_ps(kf, _mm256_set1_ps(c.du[ax]), _mm256_set1_ps(c.u0[ax]));
    u = _mm256_min_ps(_mm256_max_ps(u, zero), _mm256_set1_ps(c.umax[ax]));
    const __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(u), _mm256_set1_epi32(c.imax[ax]));
    f[ax] = _mm256_sub_ps(u, _mm256_cvtepi32_ps(i));
    _mm256_store_si256(reinterpret_cast<__m256i*>(ii[ax]), i);
  }
  // gradientAt: a voxel's 4 int16 are one 64-bit element; indices in those elements.
  alignas(32) int64_t vox[8];
  for (int l = 0; l < 8; ++l)
    vox[l] = (int64_t)ii[0][l] + (int64_t)c.gdims[0] * ((int64_t)ii[1][l] + (int64_t)c.gdims[1] * ii[2][l]);
  const auto* base = reinterpret_cast<const long long*>(c.grad);
  // The corner `off` elements away: x, y, z components of the eight lanes. Read by gather
  // instructions or one lane at a time, as the voxels are (classifyPacket).
  const __m256i vox_lo = _mm256_load_si256(reinterpret_cast<const __m256i*>(vox));
  const __m256i vox_hi = _mm256_load_si256(reinterpret_cast<const __m256i*>(vox + 4));
  auto corner = [&](int64_t off, __m256 g[3]) {
    const long long* q = base + off;
    __m256 lo4, hi4;
    if (c.gather) {
      lo4 = _mm256_castsi256_ps(_mm256_i64gather_epi64(q, vox_lo, sizeof(long long)));
      hi4 = _mm256_castsi256_ps(_mm256_i64gather_epi64(q, vox_hi, sizeof(long long)));
    } else {
      lo4 = _mm256_castsi256_ps(_mm256_setr_epi64x(q[vox[0]], q[vox[1]], q[vox[2]], q[vox[3]]));
      hi4 = _mm256_castsi256_ps(_mm256_setr_epi64x(q[vox[4]], q[vox[5]], q[vox[6]], q[vox[7]]));
    }
    // Dwords (x | y << 16) and (z | 0 << 16) of the eight lanes, in lane order.
    const __m256i xy = _mm256_castpd_si256(_mm256_permute4x64_pd(
        _mm256_castps_pd(_mm256_shuffle_ps(lo4, hi4, 0x88)), 0xD8));
    const __m256i z0 = _mm256_castpd_si256(_mm256_permute4x64_pd(
        _mm256_castps_pd(_mm256_shuffle_ps(lo4, hi4, 0xDD)), 0xD8));
    g[0] = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(xy, 16), 16));
    g[1] = _mm256_cvtepi32_ps(_mm256_srai_epi32(xy, 16));
    g[2] = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(z0, 16), 16));
  };
  auto lerp = [](__m256 x, __m256 y, __m256 t) { return _mm256_fmadd_ps(t, _mm256_sub_ps(y, x), x); };
  const int64_t sx = c.gstride[0] / 4, sy = c.gstride[1] / 4, sz = c.gstride[2] / 4;
  // lx(q) = lerp(q, q + sx, f0) per component, as gradientAt.
  auto lx = [&](int64_t q, __m256 out[3]) {
    __m256 p0[3], p1[3];
    corner(q, p0);
    corner(q + sx, p1);
    for (int k = 0; k < 3; ++k) out[k] = lerp(p0[k], p1[k], f[0]);
  };
  __m256 c00[3], c10[3], c01[3], c11[3], g[3];
  lx(0, c00);
  lx(sy, c10);
  lx(sz, c01);
  lx(sy + sz, c11);
  const __m256 inv_scale = _mm256_set1_ps(1.0f / GradientVolume::kScale);
  for (int k = 0; k < 3; ++k)
    g[k] = _mm256_mul_ps(lerp(lerp(c00[k], c10[k], f[1]), lerp(c01[k], c11[k], f[1]), f[2]), inv_scale);
  // shadeFactors; lanes with no direction get diffuse 1 and no highlight, as its branch does.
  const __m256 sign = _mm256_set1_ps(-0.0f), flat = _mm256_set1_ps((float)kFlatGradient);
  __m256 steep = zero;
  for (int k = 0; k < 3; ++k) steep = _mm256_or_ps(steep, _mm256_cmp_ps(_mm256_andnot_ps(sign, g[k]), flat, _CMP_GE_OQ));
  __m256 len2 = zero, nl = zero, nh = zero;
  for (int k = 0; k < 3; ++k) {
    const __m256 gw = _mm256_mul_ps(g[k], _mm256_set1_ps(c.inv_cell[k]));
    len2 = _mm256_fmadd_ps(gw, gw, len2);
    nl = _mm256_fmadd_ps(gw, _mm256_set1_ps(c.light[k]), nl);
    nh = _mm256_fmadd_ps(gw, _mm256_set1_ps(c.half[k]), nh);
  }
  const __m256 inv_len = _mm256_div_ps(one, _mm256_sqrt_ps(_mm256_blendv_ps(one, len2, steep)));
  const __m256 diffuse = _mm256_blendv_ps(one, _mm256_mul_ps(_mm256_andnot_ps(sign, nl), inv_len), steep);
  __m256 highlight = zero;
  if (c.ks > 0) {
    constexpr int last = HighlightTable::kEntries - 1;
    const __m256 t = _mm256_mul_ps(_mm256_min_ps(_mm256_mul_ps(_mm256_andnot_ps(sign, nh), inv_len), one),
                                   _mm256_set1_ps((float)last));
    const __m256i jv = _mm256_min_epi32(_mm256_cvttps_epi32(t), _mm256_set1_epi32(last - 1));
    alignas(32) int32_t j[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(j), jv);
    const float* hl = c.highlight;
    const __m256 h0 = _mm256_setr_ps(hl[j[0]], hl[j[1]], hl[j[2]], hl[j[3]], hl[j[4]], hl[j[5]], hl[j[6]], hl[j[7]]);
    ++hl;
    const __m256 h1 = _mm256_setr_ps(hl[j[0]], hl[j[1]], hl[j[2]], hl[j[3]], hl[j[4]], hl[j[5]], hl[j[6]], hl[j[7]]);
    const __m256 h = _mm256_fmadd_ps(_mm256_sub_ps(t, _mm256_cvtepi32_ps(jv)), _mm256_sub_ps(h1, h0), h0);
    highlight = _mm256_blendv_ps(zero, h, steep);
  }
  const __m256 scale = _mm256_fmadd_ps(_mm256_set1_ps(c.kd), diffuse, _mm256_set1_ps(c.ka));
  const __m256 add_a = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(c.ks), highlight), a);
  for (int k = 0; k < 3; ++k)
    rgba[k] = _mm256_blendv_ps(rgba[k], _mm256_min_ps(_mm256_fmadd_ps(rgba[k], scale, add_a), a), lit_lanes);
}

#else
// The portable kernel: one sample at a time (shadePacket is these operations in eight lanes).

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
  auto lerp = [](float a, float b, float t) { return std::fma(t, b - a, a); };
  for (int a = 0; a < 3; ++a) {
    auto lx = [&](const int16_t* q) { return lerp((float)q[a], (float)q[a + sx], f[0]); };
    const float v = lerp(lerp(lx(p), lx(p + sy), f[1]), lerp(lx(p + sz), lx(p + sy + sz), f[1]), f[2]);
    g[a] = v * (1.0f / GradientVolume::kScale);
  }
}

inline void shadeSample(const Consts& c, int64_t k, float pc[4]) {
  if (pc[3] <= 0) return;
  float g[3], scale, add;
  gradientAt(c, k, g);
  shadeFactors(c, g, scale, add);
  for (int ch = 0; ch < 3; ++ch) pc[ch] = std::min(pc[3], std::fma(pc[ch], scale, add * pc[3]));
}
#endif
