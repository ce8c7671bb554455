// What a frame asks of the stages (FrameParams::work and regions): plain data types, split
// from protocol.h for length; their byte layout is stated there, with FrameParams'.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/bricks.h"
#include "common/image.h"

namespace tessera::proto {

struct BrickAssignment {
  uint32_t renderer = 0; BrickBox brick;
  bool operator==(const BrickAssignment&) const = default;
};
// Sort-first: one screen tile drawn by `renderer`, routed by `compositor`.
struct TileAssignment {
  uint32_t renderer = 0, compositor = 0;
  Rect tile;
  bool operator==(const TileAssignment&) const = default;
};
struct CompositorRegion {
  uint32_t compositor = 0; Rect region; std::string endpoint;
  bool operator==(const CompositorRegion&) const = default;
};
enum class FrameMode : uint8_t { SortLast = 1, SortFirst = 2, Last = SortFirst };
// Binary swap (swap_plan.h): where one renderer takes the pieces its partners send it.
struct SwapPeer {
  uint32_t renderer = 0; std::string endpoint;
  bool operator==(const SwapPeer&) const = default;
};
// Sort-last: renderers draw bricks of the volume over the whole image; compositors blend
// every brick's piece of their region in `order`. With a swap plan the renderers composite
// among themselves by binary swap, each ending with its band of the whole image, finished,
// which it sends the display as Strips (as a compositor would): the frame has no regions and
// no compositor takes part in it.
struct SortLastWork {
  std::vector<BrickAssignment> bricks;       // one per renderer that has work
  std::vector<int> order;                    // brick indices (into `bricks`) front to back
  std::vector<SwapPeer> swap;                // empty: direct send
  bool operator==(const SortLastWork&) const = default;
};
// Sort-first: renderers draw whole scenes into screen tiles; compositors only route them.
struct SortFirstWork {
  std::vector<TileAssignment> tiles;
  bool operator==(const SortFirstWork&) const = default;
};

}  // namespace tessera::proto
