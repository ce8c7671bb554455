// Binary swap (Ma et al. 1994; IceT's and Cao et al.'s schedule) between the renderers of a
// sort-last frame: instead of every renderer sending its whole brick image to the
// compositors (direct send), renderers pair up in log2(R) rounds (R a power of two; others
// fold first, below); in each round both partners hold the same part of the image, each
// keeps one half and sends the other, and blends what it receives with what it kept. After
// the last round every renderer holds the finished image of one band, 1/R of the frame, and
// sends only that on.
//
// Partners are paired by their bricks' places in the frame's visibility order, not by
// rank: round j pairs places that differ in bit j, so every blend joins two runs of bricks
// that are consecutive front to back, and "over" (associative) gives the one-process image
// for any view. The lower place keeps the upper half of the rows. A count that is not a
// power of two folds first (proto::swapSlot): 3 renderers take 2 rounds, 6 take 3.
//
// A round with an empty `send` only receives (the fold's receiver keeps the whole frame);
// one with an empty `keep` only sends (the folding renderer, whose plan has no band).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/image.h"
#include "common/wire/protocol.h"

namespace tessera::renderer {

struct SwapRound {
  uint32_t partner = 0;         // rank
  std::string endpoint;         // where the partner takes pieces
  Rect keep, send;              // screen rows kept and sent this round (halves of the same part)
  bool partner_in_front = false;
};

struct SwapPlan {
  uint32_t brick = 0;           // this renderer's brick (index into FrameParams bricks)
  std::vector<SwapRound> rounds;
  Rect band;                    // what this renderer holds, finished, after the last round (empty: none)
  bool folded = false;          // it sends its whole image to a partner and is done
};

// This renderer's rounds in frame p; nullopt when the frame has no swap plan or no brick of it.
std::optional<SwapPlan> planSwap(const proto::FrameParams& p, uint32_t me);

}  // namespace tessera::renderer
