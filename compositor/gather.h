// Gathering the parts of each frame: they arrive in any order, possibly before the
// FrameParams that describe them, possibly stale (older epoch) or malformed. A frame is
// ready when it has its parameters and every part: sort-last, one piece from every brick;
// sort-first, one packed framebuffer from every renderer whose tiles this compositor routes.
//
// Memory is bounded whatever peers send. Frames with FrameParams are bounded by the
// master's frames-in-flight window, and their parts by the FrameParams (one per brick or
// routed renderer); they are never evicted. Parts that wait for their FrameParams (they
// can legitimately beat them only by the PUB-vs-PUSH race) are accepted only for frames
// at most kAheadWithoutParams past the newest FrameParams, only for members of the newest
// FrameParams (same epoch), and only within a byte budget; nearer frames evict farther ones.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/wire/cancelled_frames.h"
#include "common/wire/protocol.h"

namespace tessera::compositor {

class Gather {
 public:
  // The master's --window is at most 64 frames in flight, so no real part is further
  // ahead of the newest FrameParams this compositor has seen.
  static constexpr uint64_t kAheadWithoutParams = 64;
  static constexpr size_t kDefaultWaitingBudget = 32u << 20;  // bytes: waitingBudget(512, 512)
  // Parts beat their FrameParams only by the PUB-vs-PUSH race: about one frame's parts.
  // Budget: 8 parts the size of the whole image in rgba32f (16 bytes a pixel): a frame of
  // 8 bricks whose pieces all cover the image in the largest format, far more in practice.
  static size_t waitingBudget(int width, int height) { return 8 * 16 * size_t(width) * size_t(height); }

  explicit Gather(uint32_t rank, size_t waiting_budget = kDefaultWaitingBudget)
      : rank_(rank), waiting_budget_(waiting_budget) {}
  // All return "" when accepted (or quietly discarded: a part of a cancelled frame), else the
  // reason the message is dropped.
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
  // The oldest frame with FrameParams this compositor waits on and the first renderer whose
  // part of it is not here: what its heartbeats tell the master it awaits.
  std::optional<std::pair<uint64_t, uint32_t>> awaited() const;
  // Pixel bytes held by parts that wait for their FrameParams.
  size_t waitingBytes() const;
  // Reasons for parts dropped after they were accepted (their FrameParams disagreed, or
  // they waited too far ahead or were evicted for nearer frames): one per part.
  std::vector<std::string> takeLateDrops();

 private:
  struct Frame {
    std::optional<proto::FrameParams> params;
    std::map<uint32_t, proto::Piece> pieces;              // by brick
    std::map<uint32_t, proto::Framebuffer> framebuffers;  // by renderer
  };
  // What the newest FrameParams say about who may send parts.
  struct Membership {
    uint64_t frame = 0;
    uint32_t epoch = 0;
    size_t bricks = 0;
    std::set<uint32_t> routed;  // sort-first: renderers whose tiles are routed here
  };
  std::string check(const proto::FrameParams& p, const proto::Piece& piece) const;
  std::string check(const proto::FrameParams& p, const proto::Framebuffer& fb) const;
  std::string checkWaiting(const proto::Piece& piece) const;
  std::string checkWaiting(const proto::Framebuffer& fb) const;
  std::string admitWaiting(uint64_t frame, size_t bytes);
  void dropWaiting(std::map<uint64_t, Frame>::iterator it, const std::string& why);
  std::set<uint32_t> routedRenderers(const proto::FrameParams& p) const;
  template <class Part>
  std::string add(Part part, uint32_t key, std::map<uint32_t, Part> Frame::*parts, const char* what);

  uint32_t rank_;
  size_t waiting_budget_;
  std::optional<Membership> newest_;
  std::vector<std::string> late_drops_;
  uint32_t epoch_ = 0;
  uint64_t next_expected_ = 0;  // frames below this are finished
  // The frames the latest cancel (FrameParams::first_wanted) gave up: their late parts are
  // expected, not faults, and are discarded without a word.
  CancelledFrames cancelled_;
  std::map<uint64_t, Frame> frames_;
};

}  // namespace tessera::compositor
