// PNG (written by png_encode.cpp, read by libpng; straight alpha), PAM (premultiplied rgba8)
// and raw float image files.
#include "common/io/image_io.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "common/io/png_encode.h"

namespace tessera {

namespace {

struct FileCloser {
  void operator()(FILE* f) const { if (f) std::fclose(f); }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

uint8_t clampByte(double v) {
  v = std::floor(v + 0.5);
  return (uint8_t)(v < 0 ? 0 : (v > 255 ? 255 : v));
}

// A premultiplied channel c with alpha a over background channel b (all in [0, 1]), 8-bit.
uint8_t overBackground(double c, double a, double b) { return clampByte(255.0 * (c + (1 - a) * b)); }

// Premultiplied float RGBA -> 8-bit straight (or opaque over a background) RGBA.
template <class Get>
std::vector<uint8_t> toStraight(int w, int h, Get get, const std::optional<std::array<double, 3>>& bg) {
  std::vector<uint8_t> out((size_t)w * h * 4);
  for (size_t i = 0; i < (size_t)w * h; ++i) {
    double c[4];
    for (int k = 0; k < 4; ++k) {
      c[k] = get(4 * i + k);
      if (!std::isfinite(c[k])) c[k] = 0;
      c[k] = std::clamp(c[k], 0.0, 1.0);
    }
    uint8_t* o = &out[4 * i];
    if (bg) {
      for (int k = 0; k < 3; ++k) o[k] = overBackground(c[k], c[3], (*bg)[k]);
      o[3] = 255;
    } else if (c[3] > 0) {
      for (int k = 0; k < 3; ++k) o[k] = clampByte(255.0 * std::min(1.0, c[k] / c[3]));
      o[3] = clampByte(255.0 * c[3]);
    } else {
      o[0] = o[1] = o[2] = o[3] = 0;
    }
  }
  return out;
}

void writeRows(const std::string& path, int w, int h, const std::vector<uint8_t>& rgba) {
  const std::vector<uint8_t> bytes = encodePngRgba(path, w, h, rgba.data());
  FilePtr f(std::fopen(path.c_str(), "wb"));
  if (!f) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  if (std::fwrite(bytes.data(), 1, bytes.size(), f.get()) != bytes.size() || std::fflush(f.get()) != 0)
    fail(path, std::string("cannot write: ") + std::strerror(errno));
}

}  // namespace

// Straight alpha from premultiplied rgba8 by table, once per (alpha, value) pair instead of
// per channel of every pixel: round(255 * v / a), ties up, in integers (exact).
static std::vector<uint8_t> unpremultiply8(const Image8& img) {
  static const auto table = [] {
    std::vector<uint8_t> t(256 * 256);
    for (int a = 1; a < 256; ++a)
      for (int v = 0; v < 256; ++v) t[a * 256 + v] = (uint8_t)std::min(255, (510 * v + a) / (2 * a));
    return t;
  }();
  std::vector<uint8_t> out(img.px.size());
  for (size_t i = 0; i < img.px.size(); i += 4) {
    const uint8_t a = img.px[i + 3];
    if (a == 0) continue;  // out is zero-initialised: transparent black
    const uint8_t* row = &table[a * 256];
    out[i] = row[img.px[i]];
    out[i + 1] = row[img.px[i + 1]];
    out[i + 2] = row[img.px[i + 2]];
    out[i + 3] = a;
  }
  return out;
}

std::optional<std::array<double, 3>> backgroundColour(const std::vector<double>& rgb) {
  if (rgb.empty()) return std::nullopt;
  if (rgb.size() != 3) throw std::invalid_argument("background: expected r,g,b, got " + std::to_string(rgb.size()) + " values");
  for (double v : rgb)
    if (!(v >= 0 && v <= 1)) throw std::invalid_argument("background: " + std::to_string(v) + " is not in [0, 1]");
  return std::array<double, 3>{rgb[0], rgb[1], rgb[2]};
}

// Opaque over a background by table: every (channel, alpha, value) result computed once per
// background with toStraight's own arithmetic (so the bytes are the same), then one lookup a
// channel (the web view's lossless 1024^2 frame: ~5 ms less).
static std::vector<uint8_t> overBackground8(const Image8& img, const std::array<double, 3>& bg) {
  thread_local std::array<double, 3> table_bg{-1, -1, -1};
  thread_local std::vector<uint8_t> table;  // [channel][alpha][value]
  if (table.empty() || table_bg != bg) {
    backgroundColour({bg[0], bg[1], bg[2]});  // throws unless every channel is in [0, 1]
    table.resize(3 * 256 * 256);
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 256; ++a)
        for (int v = 0; v < 256; ++v) table[(k * 256 + a) * 256 + v] = overBackground(v / 255.0, a / 255.0, bg[k]);
    table_bg = bg;
  }
  std::vector<uint8_t> out(img.px.size());
  for (size_t i = 0; i < img.px.size(); i += 4) {
    const size_t a = img.px[i + 3];
    for (int k = 0; k < 3; ++k) out[i + k] = table[(k * 256 + a) * 256 + img.px[i + k]];
    out[i + 3] = 255;
  }
  return out;
}

std::vector<uint8_t> pngPixels(const Image8& img, std::optional<std::array<double, 3>> background) {
  return background ? overBackground8(img, *background) : unpremultiply8(img);
}

void writePng(const std::string& path, const Image8& img, std::optional<std::array<double, 3>> background) {
  writeRows(path, img.width, img.height, pngPixels(img, background));
}

std::vector<uint8_t> encodePng(const Image8& img, std::optional<std::array<double, 3>> background) {
  return encodePngRgba("PNG in memory", img.width, img.height, pngPixels(img, background).data());
}

void writePng(const std::string& path, const ImageF& img, std::optional<std::array<double, 3>> background) {
  auto rgba = toStraight(img.width, img.height, [&](size_t i) { return (double)img.px[i]; }, background);
  writeRows(path, img.width, img.height, rgba);
}

// libpng's simplified API: it normalises every PNG flavour (palette, grey, 16-bit, no
// alpha) to 8-bit straight RGBA and reports a damaged file as an error message.
Image8 readPng(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    std::string why = png.message;
    png_image_free(&png);
    if (!std::filesystem::exists(path)) fail(path, "cannot open: no such file");
    fail(path, "not a valid PNG file (" + why + ")");
  }
  png.format = PNG_FORMAT_RGBA;
  if (png.width > 16384 || png.height > 16384) {
    png_image_free(&png);
    fail(path, "image " + std::to_string(png.width) + "x" + std::to_string(png.height) + " larger than 16384x16384");
  }
  std::vector<uint8_t> rows(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, rows.data(), 0, nullptr))
    fail(path, std::string("not a valid PNG file (") + png.message + ")");
  Image8 img((int)png.width, (int)png.height);
  for (size_t i = 0; i < (size_t)img.width * img.height; ++i) {
    const uint8_t* s = &rows[4 * i];
    uint8_t* d = &img.px[4 * i];
    for (int k = 0; k < 3; ++k) d[k] = (uint8_t)((s[k] * s[3] + 127) / 255);  // premultiply, rounded
    d[3] = s[3];
  }
  return img;
}

void writePam(const std::string& path, const Image8& img) {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  out << "P7\nWIDTH " << img.width << "\nHEIGHT " << img.height
      << "\nDEPTH 4\nMAXVAL 255\nTUPLTYPE RGB_ALPHA_PREMULTIPLIED\nENDHDR\n";
  out.write(reinterpret_cast<const char*>(img.px.data()), (std::streamsize)img.px.size());
  if (!out) fail(path, "write failed");
}

void writePam(const std::string& path, const ImageF& img) { writePam(path, toRGBA8(img)); }

Image8 readPam(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::string line;
  if (!std::getline(in, line) || line != "P7") fail(path, "not a PAM file (expected 'P7' on the first line)");
  long long w = -1, h = -1, depth = -1, maxval = -1;
  std::string tuple;
  for (int n = 0; n < 16 && std::getline(in, line) && line != "ENDHDR"; ++n) {
    std::istringstream f(line);
    std::string key;
    f >> key;
    if (key == "WIDTH") f >> w;
    else if (key == "HEIGHT") f >> h;
    else if (key == "DEPTH") f >> depth;
    else if (key == "MAXVAL") f >> maxval;
    else if (key == "TUPLTYPE") f >> tuple;
  }
  if (line != "ENDHDR") fail(path, "PAM header has no ENDHDR line");
  if (depth != 4 || maxval != 255 || tuple != "RGB_ALPHA_PREMULTIPLIED")
    fail(path, "expected DEPTH 4, MAXVAL 255, TUPLTYPE RGB_ALPHA_PREMULTIPLIED");
  if (w < 1 || h < 1 || w > 65536 || h > 65536) fail(path, "PAM size out of range");
  Image8 img((int)w, (int)h);
  if (!in.read(reinterpret_cast<char*>(img.px.data()), (std::streamsize)img.px.size()))
    fail(path, "PAM file is shorter than WIDTH x HEIGHT x 4 bytes");
  return img;
}

void writeRawF32(const std::string& path, const ImageF& img) {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail(path, "cannot open for writing");
  auto put32 = [&](uint32_t v) {
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    out.write(reinterpret_cast<const char*>(b), 4);
  };
  out.write("TSRAWF32", 8);
  put32((uint32_t)img.width);
  put32((uint32_t)img.height);
  for (float v : img.px) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    put32(u);
  }
  if (!out) fail(path, "write failed");
}

}  // namespace tessera
