// Image files: PNG (8-bit RGBA, straight alpha, as PNG requires) and raw RGBA32F.
// Functions throw std::runtime_error naming the file on failure.
#pragma once
#include <array>
#include <optional>
#include <string>

#include "common/image.h"

namespace tessera {

// Un-premultiplies with rounding; with a background, composites over it instead (opaque).
void writePng(const std::string& path, const Image8& img,
              std::optional<std::array<double, 3>> background = std::nullopt);
void writePng(const std::string& path, const ImageF& img,
              std::optional<std::array<double, 3>> background = std::nullopt);
// Reads an RGBA PNG back into premultiplied rgba8 (for tests and tools).
Image8 readPng(const std::string& path);
// Premultiplied RGBA32F, little-endian, with a 16-byte header "TSRAWF32" w h.
void writeRawF32(const std::string& path, const ImageF& img);

}  // namespace tessera
