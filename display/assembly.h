// Assembling each frame from its strips: they arrive in any order, possibly before the
// FrameParams that describe them (PUB vs PUSH), possibly from an earlier issue of the frame
// (older epoch) after a stage came or went. A frame is complete when it has FrameParams and
// strips of the same epoch from every source the frame names: the compositors with a region
// in it, or in a binary-swap frame the renderers of the swap (each sends its finished band);
// frames are shown in order.
//
// Memory is bounded whatever members send: frames with FrameParams by the master's
// frames-in-flight window and their strips by their sources (the display refuses a stream
// larger than a whole frame); strips that wait for FrameParams
// only kAheadWithoutParams frames past the newest FrameParams, only from members of its
// epoch, and within a byte budget (nearer frames evict farther ones).
#pragma once
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/wire/cancelled_frames.h"
#include "common/wire/protocol.h"

namespace tessera::display {

class Assembly {
 public:
  using Clock = std::chrono::steady_clock;
  // The master's --in-flight is at most 64 frames in flight: no real strips are further ahead.
  static constexpr uint64_t kAheadWithoutParams = 64;

  // Who sent strips: ranks of compositors and renderers overlap.
  struct Source {
    proto::Role role = proto::Role::Compositor;
    uint32_t rank = 0;
    auto operator<=>(const Source&) const = default;
  };
  // The sources frame p waits for.
  static std::vector<Source> sourcesOf(const proto::FrameParams& p);
  // The part of the image a source of frame p owns: its region, or its binary-swap band.
  static Rect areaOf(const proto::FrameParams& p, const Source& s);

  struct Frame {
    std::optional<proto::FrameParams> params;
    std::map<Source, proto::Strips> strips;  // popNext: exactly the frame's sources
    std::map<Source, size_t> sizes;          // of each Strips message as received (compressed)
    Clock::time_point first_seen = Clock::now();
    uint64_t bytes = 0;  // popNext: of the frame's Strips messages
  };

  explicit Assembly(size_t waiting_budget) : waiting_budget_(waiting_budget) {}

  void addParams(proto::FrameParams p);
  // "" when accepted or quietly discarded (stale or cancelled: expected, not faults), else
  // why the strips are dropped. `bytes`: the message's size on the wire.
  std::string addStrips(Source from, proto::Strips s, size_t bytes);
  // The next frame in order when it is complete.
  std::optional<Frame> popNext();
  // Whether the next frame's FrameParams are here (strips alone never hold the display up).
  bool nextHasParams() const;
  // The next frame in order and the first of its sources whose strips (of its epoch) are not
  // here, when its FrameParams are: what the display's heartbeats tell the master it awaits.
  std::optional<std::pair<uint64_t, Source>> awaited() const;
  // Strips dropped after they were accepted (their FrameParams disagreed, or they waited
  // too far ahead, or were evicted): (sender's rank, reason), one per message.
  std::vector<std::pair<uint32_t, std::string>> takeLateDrops() { return std::exchange(late_drops_, {}); }

 private:
  std::string admitWaiting(const Source& from, const proto::Strips& s);
  size_t waitingBytes() const;
  std::map<uint64_t, Frame>::iterator dropWaiting(std::map<uint64_t, Frame>::iterator it, const std::string& why);
  bool complete(const Frame& f) const;

  size_t waiting_budget_;
  std::map<uint64_t, Frame> frames_;
  std::optional<proto::FrameParams> newest_;
  uint64_t next_ = 0;
  uint32_t epoch_ = 0;
  CancelledFrames cancelled_;  // the frames the latest cancels gave up
  std::vector<std::pair<uint32_t, std::string>> late_drops_;
};

}  // namespace tessera::display
