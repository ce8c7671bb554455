// A renderer's side of binary swap (swap_plan.h): its peer socket, where partners' pieces
// arrive (admitted by the master's Roster like the compositors' pieces), and the rounds of
// one frame. A partner may run ahead into its next frame, so pieces wait here until their
// round comes, bounded in count and bytes (the farthest frames go first); pieces of frames
// left behind (cancelled, or issued again under a new epoch) are discarded quietly, as they
// arrive or when a frame starts; malformed ones are dropped and counted. The rounds advance
// as pieces come and never block, so the renderer's next frame renders while a partner's
// piece is on the wire. Single-threaded (the stage's socket thread).
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "common/net/data_inbox.h"
#include "common/net/log.h"
#include "renderer/swap_layer.h"
#include "renderer/swap_plan.h"

namespace tessera::renderer {

class SwapExchange {
 public:
  // Pieces held for later rounds or frames, at most: kMaxHeld, or more for a round of a large
  // prime group (k - 1 pieces a round, and a partner's next frame's as well).
  static constexpr size_t kMaxHeld = 64;

  // `max_held_bytes`: pixel bytes held at most (a few frames' worth).
  SwapExchange(zmq::context_t& ctx, int64_t max_message, size_t max_held_bytes);
  void bind(const std::string& endpoint) { inbox_.bind(endpoint); }
  zmq::socket_t& socket() { return inbox_.socket(); }
  // Pieces older than this are of no use (the renderer's newest epoch and first wanted frame).
  void setWanted(uint32_t epoch, uint64_t first_wanted) { epoch_ = epoch, first_wanted_ = first_wanted; }
  void setMaximum(bool maximum) { maximum_ = maximum; }  // blend: maximum or minimum (blendLayer)
  void setRoster(const proto::Roster& roster, DropCounter& drops);
  void receive(DropCounter& drops);  // drains the socket (non-blocking)

  // Sends `bytes` to a partner's endpoint.
  using Send = std::function<void(const std::string& endpoint, std::vector<std::byte>&& bytes)>;

  // One frame's rounds, advanced as partners' pieces come, so that the renderer renders its
  // next frame meanwhile (at most one frame's rounds at a time). start() takes brick image
  // `img` (active within `active`), which must stay alive and unchanged until the rounds end.
  void start(const proto::FrameParams& p, uint32_t me, const SwapPlan& plan, const ImageF& img, const Rect& active);
  bool running() const { return run_.has_value(); }
  // Plays every round whose partners' pieces are held; never waits. Returns the partner whose
  // piece the round awaits, or nullopt when the rounds are over (then finish()).
  // st gets the bytes sent, the encode and the decode-and-blend times.
  std::optional<uint32_t> advance(const Send& send, proto::StageStats& st, DropCounter& drops);
  // The finished band (empty when it has no rows: proto::swapBand).
  Layer finish();
  void abandon();  // the frame was given up: a new epoch, a cancel, Shutdown, the master's loss

  // A band finish() returned, once sent: its memory serves the next frame's rounds.
  void recycle(Layer&& l);

 private:
  struct Held {
    proto::Piece piece;
    double decode_ms = 0;
  };
  struct Run {
    proto::FrameParams p;
    uint32_t me = 0;
    SwapPlan plan;
    const ImageF* img = nullptr;
    Rect active;
    size_t round = 0;     // the round being played
    bool sent = false;    // its pieces have left
    size_t front = 0, back = 0;  // partners in front and behind blended in so far
    Layer mine;           // blended so far (read after a round's first blend)
  };
  bool stale(const proto::Piece& p) const {
    return p.epoch < epoch_ || (p.epoch == epoch_ && p.frame < first_wanted_);
  }
  void accept(std::vector<DataInbox::Message> messages, DropCounter& drops);
  void evictFor(size_t bytes, DropCounter& drops);
  std::vector<float> takeSpare();
  std::optional<Held> take(const proto::FrameParams& p, uint32_t from, const Rect& region);
  std::optional<Held> takeIn(const proto::FrameParams& p, uint32_t from, const Rect& region, proto::PixelFormat format,
                             DropCounter& drops);

  DataInbox inbox_;
  size_t max_held_bytes_;
  size_t max_held_ = kMaxHeld;
  uint32_t epoch_ = 0;
  uint64_t first_wanted_ = 0;
  bool maximum_ = false;
  std::vector<Held> held_;
  size_t held_bytes_ = 0;
  std::vector<std::byte> packed_;
  std::vector<std::vector<float>> spares_;
  std::optional<Run> run_;
};

// Pieces between renderers carry at least rgba16f: each round's blend is rounded once more,
// and rgba8 rounding per round would break the 1/255 contract.
proto::PixelFormat swapFormat(proto::PixelFormat f);

}  // namespace tessera::renderer
