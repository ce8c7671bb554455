// A frame as the web view sends it: one binary WebSocket message, [u32 little-endian length
// of the header][header: JSON][image bytes]. The header says the frame's id, its kind
// ("png": lossless, the PNG sink's pixels; "jpeg": a lossy frame while the camera moves;
// "empty": nothing but background), the active region (x, y, w, h) inside the full frame
// (fw, fh), the size of the last full-quality frame the page shows it at (full: [w, h], once
// there was one), the colour of the pixels outside it (bg: the background the frame is shown
// over, as the PNG sink composites it), the status line, and, if the first input the frame answers
// came from a page, that page's numbers for it (input: {page, n}: the page times its input to
// the frame's presentation). Only the active region travels.
#pragma once
#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "common/image.h"
#include "display/sink.h"

namespace tessera::display {

struct WebFrame {
  uint64_t id = 0;
  bool lossless = false;
  std::chrono::steady_clock::time_point shown_at;  // when the display presented it
  std::vector<uint8_t> message;  // header + image: what goes on the wire
  size_t image_bytes = 0;        // of which the encoded image
};

// Encodes premultiplied `frame` over `background` (r, g, b in [0, 1]): losslessly as PNG (the
// bytes the PNG sink writes for this region with this background), or, while the camera moves
// (shown.moving), as JPEG of `jpeg_quality` (4:4:4: on these small frames it beats 4:2:0 at
// equal bytes).
WebFrame encodeWebFrame(const Image8& frame, const Shown& shown, const std::array<double, 3>& background,
                        int jpeg_quality);

}  // namespace tessera::display
