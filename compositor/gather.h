// Gathering the parts of each frame: they arrive in any order, possibly before the
// FrameParams that describe them, possibly stale (older epoch) or malformed. A frame is
// ready when it has its parameters and every part: sort-last, one piece from every brick;
// sort-first, one packed framebuffer from every renderer whose tiles this compositor routes.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/wire/protocol.h"

namespace tessera::compositor {

class Gather {
 public:
  explicit Gather(uint32_t rank) : rank_(rank) {}
  // All return "" when accepted, else the reason the message is dropped.
  std::string addParams(proto::FrameParams p);
  std::string addPiece(proto::Piece piece);
  std::string addFramebuffer(proto::Framebuffer fb);

  struct Ready {
    proto::FrameParams params;
    std::vector<proto::Piece> pieces;              // sort-last, indexed by brick
    std::vector<proto::Framebuffer> framebuffers;  // sort-first
    std::optional<Rect> region;                    // this compositor's region (none: spare this frame)
    std::vector<Rect> tiles;                       // sort-first: the tiles this compositor routes
  };
  // The oldest frame that is complete, removed from the pending set.
  std::optional<Ready> pop();
  size_t pending() const { return frames_.size(); }
  // Reasons for parts dropped when their FrameParams arrived after them.
  std::vector<std::string> takeLateDrops();

  static constexpr size_t kMaxPending = 64;  // frames; beyond this the oldest are dropped

 private:
  struct Frame {
    std::optional<proto::FrameParams> params;
    std::map<uint32_t, proto::Piece> pieces;              // by brick
    std::map<uint32_t, proto::Framebuffer> framebuffers;  // by renderer
  };
  std::string check(const proto::FrameParams& p, const proto::Piece& piece) const;
  std::string check(const proto::FrameParams& p, const proto::Framebuffer& fb) const;
  std::set<uint32_t> routedRenderers(const proto::FrameParams& p) const;
  template <class Part>
  std::string add(Part part, uint32_t key, std::map<uint32_t, Part> Frame::*parts, const char* what);

  uint32_t rank_;
  std::vector<std::string> late_drops_;
  uint32_t epoch_ = 0;
  uint64_t next_expected_ = 0;  // frames below this are finished
  std::map<uint64_t, Frame> frames_;
};

}  // namespace tessera::compositor
