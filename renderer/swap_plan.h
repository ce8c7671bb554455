// Binary swap (Ma et al. 1994; IceT's and Cao et al.'s schedule) between the renderers of a
// sort-last frame, generalised as radix-k (Peterka et al. 2009, as IceT does): instead of
// every renderer sending its whole brick image to the compositors (direct send), renderers
// composite among themselves in rounds. In a round a group of k renderers (k = 2 in every
// round for a power of two: binary swap) holds the same part of the image; each keeps one of
// k row bands of it, sends the other k - 1 bands to the members they belong to, and blends
// what it receives with what it kept. After the last round every renderer holds the finished
// image of one band, 1/R of the frame, and sends only that on.
//
// Groups are made of places in the frame's visibility order, not of ranks
// (proto::swapRadices): in round j a group's members differ only in digit j of their place,
// and each holds the blend of a run of bricks consecutive front to back, ordered by that
// digit, so every blend joins consecutive runs and "over" (associative) gives the one-process
// image for any view. Member i of a group keeps band i (band 0 on top). 3 renderers take one
// round of three, 6 a round of pairs and one of threes, 5 one round of five.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/image.h"
#include "common/wire/protocol.h"

namespace tessera::renderer {

// Another member of this renderer's group in a round.
struct SwapPartner {
  uint32_t rank = 0;
  std::string endpoint;  // where it takes pieces
  Rect send;             // the rows it keeps this round, which this renderer sends it
  int offset = 0;        // its digit minus this renderer's: < 0 in front, -1 and +1 adjacent
};

struct SwapRound {
  Rect keep;                          // screen rows kept this round (one band of the group's part)
  std::vector<SwapPartner> partners;  // by digit, front to back
};

struct SwapPlan {
  uint32_t brick = 0;           // this renderer's brick (index into FrameParams bricks)
  std::vector<SwapRound> rounds;
  Rect band;                    // what this renderer holds, finished, after the last round (empty: none)
};

// This renderer's rounds in frame p; nullopt when the frame has no swap plan or no brick of it.
std::optional<SwapPlan> planSwap(const proto::FrameParams& p, uint32_t me);

}  // namespace tessera::renderer
