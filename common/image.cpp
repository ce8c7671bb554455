// Image values and pixel kernels: cropping, quantization, "over" compositing, error metrics.
#include "common/image.h"

#include "common/cpu.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace tessera {

Rect intersect(const Rect& a, const Rect& b) {
  int x0 = std::max(a.x, b.x), y0 = std::max(a.y, b.y);
  int x1 = std::min(a.x + a.w, b.x + b.w), y1 = std::min(a.y + a.h, b.y + b.h);
  if (x1 <= x0 || y1 <= y0) return Rect{};
  return Rect{x0, y0, x1 - x0, y1 - y0};
}

Rect unite(const Rect& a, const Rect& b) {
  if (a.empty()) return b.empty() ? Rect{} : b;
  if (b.empty()) return a;
  int x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
  int x1 = std::max(a.x + a.w, b.x + b.w), y1 = std::max(a.y + a.h, b.y + b.h);
  return Rect{x0, y0, x1 - x0, y1 - y0};
}

static void checkSize(int w, int h) {
  if (w < 0 || h < 0) throw std::invalid_argument("image size must be non-negative");
}

ImageF::ImageF(int w, int h) : ImageF(w, h, {}) {}

ImageF::ImageF(int w, int h, std::vector<float>&& storage) : width(w), height(h), px(std::move(storage)) {
  checkSize(w, h);
  px.assign((size_t)w * h * 4, 0.0f);
}

void ImageF::clear(const Rect& dirty) {
  const Rect r = intersect(dirty, Rect{0, 0, width, height});
  for (int y = r.y; y < r.y + r.h; ++y) std::fill_n(at(r.x, y), 4 * (size_t)r.w, 0.0f);
}

Image8::Image8(int w, int h) : width(w), height(h) {
  checkSize(w, h);
  px.assign((size_t)w * h * 4, 0);
}

void Image8::clear(const Rect& r) {
  const Rect c = intersect(r, Rect{0, 0, width, height});
  for (int y = c.y; y < c.y + c.h; ++y) std::fill_n(at(c.x, y), 4 * (size_t)c.w, uint8_t{0});
}

namespace {
template <class Img>
Rect activeRegionImpl(const Img& img) {
  int x0 = img.width, y0 = img.height, x1 = -1, y1 = -1;
  for (int y = 0; y < img.height; ++y) {
    const auto* row = img.at(0, y);
    int first = -1, last = -1;
    for (int x = 0; x < img.width; ++x) {
      if (row[4 * x + 3] > 0) {
        if (first < 0) first = x;
        last = x;
      }
    }
    if (first < 0) continue;
    x0 = std::min(x0, first);
    x1 = std::max(x1, last);
    y0 = std::min(y0, y);
    y1 = y;
  }
  if (x1 < 0) return Rect{};
  return Rect{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}
}  // namespace

Rect activeRegion(const ImageF& img) { return activeRegionImpl(img); }
Rect activeRegion(const Image8& img) { return activeRegionImpl(img); }

#if defined(__x86_64__)
// Eight values per step where the CPU has AVX2 (cpuIsa()); same results as the scalar loop.
__attribute__((target("avx2"))) static size_t quantizeAvx2(const float* in, uint8_t* out, size_t n) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), k255 = _mm256_set1_ps(255.0f),
               half = _mm256_set1_ps(0.5f);
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {  // max_ps returns its second operand for NaN: NaN -> 0
    __m256 v = _mm256_min_ps(_mm256_max_ps(_mm256_loadu_ps(in + i), zero), one);
    __m256i q = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(v, k255), half));
    __m128i q16 = _mm_packus_epi32(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + i), _mm_packus_epi16(q16, q16));
  }
  return i;
}
#endif

void quantizeToUnorm8(const float* in, uint8_t* out, size_t n) {
  size_t i = 0;
#if defined(__x86_64__)
  if (cpuIsa() >= Isa::Avx2) i = quantizeAvx2(in, out, n);
#endif
  for (; i < n; ++i) {
    // NaN fails both comparisons and ends at 0, so a bad pixel never becomes garbage.
    float v = in[i] * 255.0f + 0.5f;
    v = v > 0.0f ? v : 0.0f;
    v = v < 255.0f ? v : 255.0f;
    out[i] = (uint8_t)v;
  }
}

Image8 toRGBA8(const ImageF& img) {
  Image8 out(img.width, img.height);
  quantizeToUnorm8(img.px.data(), out.px.data(), img.px.size());
  return out;
}

ImageF toFloat(const Image8& img) {
  ImageF out(img.width, img.height);
  const size_t n = img.px.size();
  for (size_t i = 0; i < n; ++i) out.px[i] = img.px[i] * (1.0f / 255.0f);
  return out;
}

TESSERA_CLONES void compositeOver(ImageF& dst, const ImageF& src, const Rect& r) {
  if (dst.width != src.width || dst.height != src.height)
    throw std::invalid_argument("compositeOver: image sizes differ");
  Rect c = intersect(r, Rect{0, 0, dst.width, dst.height});
  for (int y = c.y; y < c.y + c.h; ++y) {
    float* __restrict d = dst.at(c.x, y);
    const float* __restrict s = src.at(c.x, y);
    const int n = c.w;
    // Straight-line per-pixel body: GCC -O3 turns this into SIMD (SLP over the 4 lanes).
    for (int p = 0; p < n; ++p) {
      const float k = 1.0f - d[4 * p + 3];
      d[4 * p + 0] += k * s[4 * p + 0];
      d[4 * p + 1] += k * s[4 * p + 1];
      d[4 * p + 2] += k * s[4 * p + 2];
      d[4 * p + 3] += k * s[4 * p + 3];
    }
  }
}

namespace {
template <class Img, class F>
ImageError compareImpl(const Img& a, const Img& b, F toUnit) {
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("compare: image sizes differ (" + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                                std::to_string(b.height) + ")");
  ImageError e;
  double sum = 0;
  const size_t n = a.px.size();
  for (size_t i = 0; i < n; ++i) {
    double d = std::abs(toUnit(a.px[i]) - toUnit(b.px[i]));
    if (!(d <= e.max_abs)) e.max_abs = d;  // also propagates NaN
    sum += d * d;
  }
  double mse = n ? sum / (double)n : 0.0;
  e.rmse = std::sqrt(mse);
  e.psnr = mse == 0 ? std::numeric_limits<double>::infinity() : 10.0 * std::log10(1.0 / mse);
  return e;
}
}  // namespace

ImageError compare(const ImageF& a, const ImageF& b) {
  return compareImpl(a, b, [](float v) { return (double)v; });
}
ImageError compare(const Image8& a, const Image8& b) {
  return compareImpl(a, b, [](uint8_t v) { return v / 255.0; });
}

}  // namespace tessera
