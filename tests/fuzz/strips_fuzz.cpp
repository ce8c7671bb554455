// Routes arbitrary bytes as a strip stream and as a packed framebuffer into a small image.
// ASan catches any write outside the destination; the counters must stay consistent.
#include <cstdlib>
#include <cstring>

#include "common/wire/strips.h"

using namespace tessera;

namespace {

// Built by hand so the fuzzer needs no image.cpp: exactly w*h pixels, nothing spare.
Image8 blank(int w, int h) {
  Image8 img;
  img.width = w;
  img.height = h;
  img.px.assign(4 * size_t(w) * size_t(h), 0);
  return img;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  const int w = data[0] % 48, h = data[1] % 24;  // zero-sized destinations included
  const uint8_t display = data[2] % 3;
  const int fb_w = 1 + data[3] % 40;
  std::vector<uint8_t> rest(data + 4, data + size);  // own allocation: overreads are caught

  Image8 dst = blank(w, h);
  RouteStats s = routeStrips(rest, dst, display);
  if (s.strips_written < 0 || s.strips_rejected < 0) std::abort();
  if (size_t(s.strips_written + s.strips_rejected) * 8 > rest.size()) std::abort();

  Image8 fb = blank(fb_w, int(rest.size() / (4 * size_t(fb_w))));
  if (!fb.px.empty()) std::memcpy(fb.px.data(), rest.data(), fb.px.size());
  Image8 dst2 = blank(w, h);
  RouteStats f = routeFramebuffer(fb, dst2, display);
  if (f.strips_written > fb.height * (fb_w / kStripHeaderPixels)) std::abort();
  return 0;
}
