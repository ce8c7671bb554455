// tessera-web-codec-sweep: what the web view's frames cost in bytes and error. For each
// frame given (premultiplied PAM files, e.g. tessera-render --premultiplied of the scene at
// the full size and at the reduced sizes of the interaction's ladder), as the web view sends
// them (active region, over the background): the lossless PNG (bytes, encode ms) and JPEG at
// each quality with 4:2:0 and 4:4:4 chroma (bytes, encode ms, PSNR and largest error against
// the lossless pixels). Writes CSV and prints a Markdown table. Single thread.
//   tessera-web-codec-sweep --csv out.csv frame1024.pam frame512.pam ...
#include <turbojpeg.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/clock.h"
#include "common/image.h"
#include "common/io/image_io.h"
#include "display/web_frame.h"

namespace {

using tessera::Clock;
using tessera::msSince;
const std::array<double, 3> kBg{32 / 255.0, 32 / 255.0, 36 / 255.0};  // the web view's default

// Encodings timed per frame and codec, the best kept (the first pays for the encoders' buffers).
constexpr int kRepeats = 5;

struct Jpeg {
  size_t bytes = 0;
  double encode_ms = 0, psnr = 0;
  int max_error = 0;
};

// JPEG of opaque rgba rows (w x h), decoded again and compared with them.
Jpeg jpeg(const std::vector<uint8_t>& rgba, int w, int h, int quality, int subsampling) {
  std::unique_ptr<void, int (*)(tjhandle)> enc(tjInitCompress(), tjDestroy), dec(tjInitDecompress(), tjDestroy);
  unsigned char* out = nullptr;
  unsigned long size = 0;
  Jpeg j;
  j.encode_ms = 1e300;
  for (int i = 0; i < kRepeats; ++i) {  // the best of a few: the web view encodes frame after frame
    tjFree(out);
    out = nullptr;
    const auto t0 = Clock::now();
    if (tjCompress2(enc.get(), rgba.data(), w, 0, h, TJPF_RGBA, &out, &size, subsampling, quality, TJFLAG_FASTDCT) != 0)
      throw std::runtime_error(tjGetErrorStr2(enc.get()));
    j.encode_ms = std::min(j.encode_ms, msSince(t0));
  }
  j.bytes = size;
  std::vector<uint8_t> back(rgba.size());
  if (tjDecompress2(dec.get(), out, size, back.data(), w, 0, h, TJPF_RGBA, 0) != 0)
    throw std::runtime_error(tjGetErrorStr2(dec.get()));
  tjFree(out);
  double sq = 0;
  size_t n = 0;
  for (size_t i = 0; i < rgba.size(); i += 4)
    for (int c = 0; c < 3; ++c, ++n) {
      const int d = int(back[i + c]) - int(rgba[i + c]);
      sq += double(d) * d;
      j.max_error = std::max(j.max_error, std::abs(d));
    }
  const double mse = sq / double(n);
  j.psnr = mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : 99;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tessera-web-codec-sweep: bytes and error of the web view's frames"};
  std::vector<std::string> frames;
  std::string csv_path = "web-codec-sweep.csv";
  app.add_option("frames", frames, "premultiplied PAM frames")->required();
  app.add_option("--csv", csv_path, "CSV output")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::ofstream csv(csv_path);
  csv << "frame,width,height,region_w,region_h,codec,quality,bytes,encode_ms,psnr_db,max_error\n";
  std::printf("| frame | region | codec | bytes | encode ms | PSNR | max error |\n|---|---|---|---|---|---|---|\n");
  for (const std::string& path : frames) {
    const tessera::Image8 frame = tessera::readPam(path);
    const tessera::Rect r = tessera::activeRegion(frame);
    tessera::Image8 region(r.w, r.h);
    for (int y = 0; y < r.h; ++y)
      std::copy_n(frame.at(r.x, r.y + y), size_t(r.w) * 4, region.at(0, y));
    const auto rgba = tessera::pngPixels(region, kBg);
    const std::string size = std::to_string(frame.width) + "x" + std::to_string(frame.height);
    const std::string reg = std::to_string(r.w) + "x" + std::to_string(r.h);
    double png_ms = 1e300;
    tessera::display::WebFrame png;
    for (int i = 0; i < kRepeats; ++i) {
      const auto t0 = Clock::now();
      png = tessera::display::encodeWebFrame(frame, {}, kBg, 80);
      png_ms = std::min(png_ms, msSince(t0));
    }
    csv << size << "," << frame.width << "," << frame.height << "," << r.w << "," << r.h << ",png,100,"
        << png.image_bytes << "," << png_ms << ",inf,0\n";
    std::printf("| %s | %s | PNG (lossless) | %zu | %.1f | exact | 0 |\n", size.c_str(), reg.c_str(), png.image_bytes, png_ms);
    for (int sub : {TJSAMP_420, TJSAMP_444})
      for (int q : {50, 60, 70, 80, 90, 95}) {
        const Jpeg j = jpeg(rgba, r.w, r.h, q, sub);
        const char* name = sub == TJSAMP_420 ? "jpeg420" : "jpeg444";
        csv << size << "," << frame.width << "," << frame.height << "," << r.w << "," << r.h << "," << name << "," << q
            << "," << j.bytes << "," << j.encode_ms << "," << j.psnr << "," << j.max_error << "\n";
        std::printf("| %s | %s | JPEG %s q%d | %zu | %.1f | %.1f dB | %d |\n", size.c_str(), reg.c_str(),
                    sub == TJSAMP_420 ? "4:2:0" : "4:4:4", q, j.bytes, j.encode_ms, j.psnr, j.max_error);
      }
  }
  return 0;
}
