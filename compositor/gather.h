// Gathering the pieces of each frame: they arrive in any order, possibly before the
// FrameParams that describe them, possibly stale (older epoch) or malformed. A frame is
// ready when it has its parameters and one valid piece from every brick.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/protocol.h"

namespace tessera::compositor {

class Gather {
 public:
  explicit Gather(uint32_t rank) : rank_(rank) {}
  // Both return "" when accepted, else the reason the message is dropped.
  std::string addParams(proto::FrameParams p);
  std::string addPiece(proto::Piece piece);
  // The oldest frame that is complete, removed from the pending set.
  struct Ready {
    proto::FrameParams params;
    std::vector<proto::Piece> pieces;  // indexed by brick
    std::optional<Rect> region;        // this compositor's region (none: spare this frame)
  };
  std::optional<Ready> pop();
  size_t pending() const { return frames_.size(); }
  // Reasons for pieces dropped when their FrameParams arrived after them.
  std::vector<std::string> takeLateDrops();

  static constexpr size_t kMaxPending = 64;  // frames; beyond this the oldest are dropped

 private:
  struct Frame {
    std::optional<proto::FrameParams> params;
    std::map<uint32_t, proto::Piece> pieces;
  };
  std::string check(const proto::FrameParams& p, const proto::Piece& piece) const;
  uint32_t rank_;
  std::vector<std::string> late_drops_;
  uint32_t epoch_ = 0;
  uint64_t next_expected_ = 0;  // frames below this are finished
  std::map<uint64_t, Frame> frames_;
};

}  // namespace tessera::compositor
