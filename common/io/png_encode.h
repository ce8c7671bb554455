// PNG encoding of 8-bit RGBA rows, fast enough for a display that writes every frame.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace tessera {

// A complete PNG file (8-bit RGBA, non-interlaced) of `h` rows of `w` pixels, rows top to
// bottom. Throws std::runtime_error starting with `what` on failure.
std::vector<uint8_t> encodePngRgba(const std::string& what, int w, int h, const uint8_t* rgba);

}  // namespace tessera
