// What a failing image comparison leaves behind: <stem>_expected.png, <stem>_actual.png and
// <stem>_diff.png (per pixel the largest channel difference x 16, opaque grey) in `folder`.
#pragma once
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/image.h"
#include "common/io/image_io.h"

namespace tessera::test {

// Returns "<folder>/<stem>_{expected,actual,diff}.png" for the failure message.
inline std::string writeImageMismatch(const std::filesystem::path& folder, const std::string& stem,
                                      const Image8& expected, const Image8& actual) {
  std::filesystem::create_directories(folder);
  const std::string base = (folder / stem).string();
  writePng(base + "_expected.png", expected);
  writePng(base + "_actual.png", actual);
  if (actual.width == expected.width && actual.height == expected.height) {
    Image8 d(actual.width, actual.height);
    for (size_t i = 0; i < d.px.size(); i += 4) {
      int m = 0;
      for (int c = 0; c < 4; ++c) m = std::max(m, std::abs(int(actual.px[i + c]) - int(expected.px[i + c])));
      d.px[i] = d.px[i + 1] = d.px[i + 2] = (uint8_t)std::min(255, 16 * m);
      d.px[i + 3] = 255;
    }
    writePng(base + "_diff.png", d);
  }
  return base + "_{expected,actual,diff}.png";
}

}  // namespace tessera::test
