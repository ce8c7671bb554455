// Cropping and encoding frames for the web view (PNG through image_io, libturbojpeg).
#include "display/web_frame.h"

#include <turbojpeg.h>

#include <algorithm>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "common/io/image_io.h"

namespace tessera::display {
namespace {

Image8 crop(const Image8& frame, const Rect& r) {
  Image8 out(r.w, r.h);
  for (int y = 0; y < r.h; ++y) {
    const uint8_t* src = frame.px.data() + ((size_t)(r.y + y) * frame.width + r.x) * 4;
    std::copy(src, src + (size_t)r.w * 4, out.px.data() + (size_t)y * r.w * 4);
  }
  return out;
}

std::vector<uint8_t> encodeJpeg(const Image8& region, const std::array<double, 3>& bg, int quality) {
  const std::vector<uint8_t> rgba = pngPixels(region, bg);  // opaque over the background
  std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitCompress(), tjDestroy);
  if (!tj) throw std::runtime_error("libturbojpeg: cannot start a compressor");
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  if (tjCompress2(tj.get(), rgba.data(), region.width, 0, region.height, TJPF_RGBA, &jpeg, &size, TJSAMP_444, quality,
                  TJFLAG_FASTDCT) != 0) {
    const std::string why = tjGetErrorStr2(tj.get());
    tjFree(jpeg);
    throw std::runtime_error("libturbojpeg: " + why);
  }
  std::vector<uint8_t> out(jpeg, jpeg + size);
  tjFree(jpeg);
  return out;
}

}  // namespace

WebFrame encodeWebFrame(const Image8& frame, const Shown& shown, const std::array<double, 3>& background,
                        int jpeg_quality) {
  const bool lossless = !shown.moving;
  const Rect r = activeRegion(frame);  // pixels with alpha > 0
  std::vector<uint8_t> image;
  if (r.w > 0) {
    const Image8 region = crop(frame, r);
    image = lossless ? encodePng(region, background) : encodeJpeg(region, background, jpeg_quality);
  }
  // The colour outside the region: a transparent pixel over the background, as pngPixels makes it.
  const std::vector<uint8_t> outside = pngPixels(Image8(1, 1), background);
  nlohmann::json header = {{"id", shown.id},
                                 {"kind", r.w == 0 ? "empty" : (lossless ? "png" : "jpeg")},
                                 {"moving", !lossless},
                                 {"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h},
                                 {"fw", frame.width}, {"fh", frame.height},
                                 {"bg", {outside[0], outside[1], outside[2]}},
                                 {"status", shown.status}};
  if (shown.full_width > 0) header["full"] = {shown.full_width, shown.full_height};
  if (shown.page) header["input"] = {{"page", shown.page}, {"n", shown.page_input}, {"ms", shown.input_ms}};
  const std::string text = header.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  WebFrame f;
  f.id = shown.id;
  f.lossless = lossless;
  f.image_bytes = image.size();
  const uint32_t n = (uint32_t)text.size();
  f.message.reserve(4 + text.size() + image.size());
  for (int k = 0; k < 4; ++k) f.message.push_back((uint8_t)(n >> (8 * k)));
  f.message.insert(f.message.end(), text.begin(), text.end());
  f.message.insert(f.message.end(), image.begin(), image.end());
  return f;
}

}  // namespace tessera::display
