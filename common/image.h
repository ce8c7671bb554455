// Images on the farm: premultiplied RGBA, rows top to bottom, (0,0) top left.
// ImageF (float, [0,1]) is what renderers and compositors compute in; Image8 is rgba8.
// Plain values; not thread-safe for concurrent writes to the same pixels.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tessera {

struct Rect {
  int x = 0, y = 0, w = 0, h = 0;
  bool empty() const { return w <= 0 || h <= 0; }
  long long area() const { return empty() ? 0 : (long long)w * h; }
  bool operator==(const Rect&) const = default;
};
Rect intersect(const Rect& a, const Rect& b);
Rect unite(const Rect& a, const Rect& b);  // bounding rectangle; empty operands ignored

struct ImageF {
  int width = 0, height = 0;
  std::vector<float> px;  // 4 floats per pixel, premultiplied RGBA
  ImageF() = default;
  ImageF(int w, int h);   // transparent black
  // Transparent black in `storage`'s memory: a caller that renders frame after frame passes
  // the image it no longer needs, and the new one costs a clear instead of fresh pages (a
  // 1024^2 image is 4096 pages to fault in and zero: ~5 ms of kernel time per frame).
  ImageF(int w, int h, std::vector<float>&& storage);
  // Transparent black again, clearing only `dirty` (clipped to the image): for an image whose
  // pixels outside `dirty` are transparent already, e.g. its active region. A renderer's brick
  // image covers a third of a 1024^2 frame or less, and clearing all 16 MB of it was 2% of a
  // farm renderer's time.
  void clear(const Rect& dirty);
  float* at(int x, int y) { return &px[4 * ((size_t)y * width + x)]; }
  const float* at(int x, int y) const { return &px[4 * ((size_t)y * width + x)]; }
  bool operator==(const ImageF&) const = default;
};

struct Image8 {
  int width = 0, height = 0;
  std::vector<uint8_t> px;  // 4 bytes per pixel, premultiplied RGBA
  Image8() = default;
  Image8(int w, int h);
  void clear(const Rect& r);  // transparent black inside r (clipped to the image)
  uint8_t* at(int x, int y) { return &px[4 * ((size_t)y * width + x)]; }
  const uint8_t* at(int x, int y) const { return &px[4 * ((size_t)y * width + x)]; }
  bool operator==(const Image8&) const = default;
};

// Bounding rectangle of pixels with alpha > 0 (empty Rect if none).
Rect activeRegion(const ImageF& img);
Rect activeRegion(const Image8& img);

// Round-to-nearest quantization of [0,1] floats (clamped) to bytes.
// [0,1] floats to bytes rounding to nearest (clamp, x255, +0.5, truncate; NaN -> 0): the one
// rgba8 quantizer, so the farm and tessera-render round identically. AVX2 where built for it.
void quantizeToUnorm8(const float* in, uint8_t* out, size_t n);
Image8 toRGBA8(const ImageF& img);
ImageF toFloat(const Image8& img);

// Front-to-back "over": dst = dst + (1 - dst.a) * src, per pixel, within rect r.
void compositeOver(ImageF& dst, const ImageF& src, const Rect& r);

struct ImageError {
  double max_abs = 0, rmse = 0, psnr = 0;  // over RGBA in [0,1]; psnr is +inf when equal
};
ImageError compare(const ImageF& a, const ImageF& b);
ImageError compare(const Image8& a, const Image8& b);

}  // namespace tessera
