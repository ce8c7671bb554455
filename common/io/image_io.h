// Image files: PNG (8-bit RGBA, straight alpha, as PNG requires), PAM (premultiplied rgba8,
// the farm's own values, for exact comparisons) and raw RGBA32F.
// Functions throw std::runtime_error naming the file on failure.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "common/image.h"

namespace tessera {

// The background colour of an r,g,b option (none if empty). Throws std::invalid_argument
// naming the value unless there are three numbers in [0, 1] (NaN has no colour).
std::optional<std::array<double, 3>> backgroundColour(const std::vector<double>& rgb);

// Un-premultiplies with rounding; with a background, composites over it instead (opaque).
void writePng(const std::string& path, const Image8& img,
              std::optional<std::array<double, 3>> background = std::nullopt);
// The rgba8 rows writePng writes for `img` (straight alpha, or opaque over the background).
std::vector<uint8_t> pngPixels(const Image8& img, std::optional<std::array<double, 3>> background);
// The bytes writePng writes, in memory (the web view sends the PNG sink's file).
std::vector<uint8_t> encodePng(const Image8& img, std::optional<std::array<double, 3>> background = std::nullopt);
void writePng(const std::string& path, const ImageF& img,
              std::optional<std::array<double, 3>> background = std::nullopt);
// Reads an RGBA PNG back into premultiplied rgba8 (for tests and tools).
Image8 readPng(const std::string& path);
// Premultiplied rgba8 as a Netpbm PAM file: the header
//   P7\nWIDTH w\nHEIGHT h\nDEPTH 4\nMAXVAL 255\nTUPLTYPE RGB_ALPHA_PREMULTIPLIED\nENDHDR\n
// then w*h*4 bytes, rows top to bottom, r g b a per pixel. The TUPLTYPE says the colour is
// premultiplied (Netpbm's RGB_ALPHA is straight): comparing these values is comparing what the
// farm computed, without PNG's separate rounding of colour and alpha (which can add a level).
void writePam(const std::string& path, const Image8& img);
// Quantizes with toRGBA8 (round to nearest), as the compositors do for the display.
void writePam(const std::string& path, const ImageF& img);
// Reads a file written by writePam (other tuple types are refused: they are not premultiplied).
Image8 readPam(const std::string& path);
// Premultiplied RGBA32F, little-endian, with a 16-byte header "TSRAWF32" w h.
void writeRawF32(const std::string& path, const ImageF& img);

}  // namespace tessera
