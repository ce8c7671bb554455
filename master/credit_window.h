// The credit window: at most `in_flight` frames issued and not yet done; who has delivered
// for each of them (renderer and compositor Stats, the display's FrameDone); and the
// per-frame deadline, derived from recent frame latencies, after which the oldest frame's
// missing stage is blamed. Plain values, no sockets; time is passed in.
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "common/wire/protocol.h"
#include "master/refinement.h"

namespace tessera::master {

struct DeadlineOptions {
  double start_s = 30.0;   // before any frame completed (loading, first frames)
  double floor_s = 3.0;    // never tighter than this
  double factor = 8.0;     // x the median of the last kSamples frame latencies
};

class CreditWindow {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr size_t kSamples = 16;

  struct InFlight {
    Clock::time_point issued;
    uint32_t epoch = 0;  // Stats of another epoch are for an earlier issue of the frame
    FrameSpec spec;
    std::set<uint32_t> renderers, compositors;  // expected to report Stats
    std::set<uint32_t> renderers_in, compositors_in;  // reported
  };
  // Who a frame still waits for: renderers without Stats, then compositors without Stats,
  // then the display (its FrameDone) when everyone else has reported.
  struct Waiting {
    std::vector<uint32_t> renderers, compositors;
    bool display = false;
    // Who sends the display this frame's strips: its compositors, or in a binary-swap frame
    // (one without compositors) its renderers, their bands.
    proto::Role display_sources = proto::Role::Compositor;
  };

  CreditWindow(int in_flight, DeadlineOptions deadline) : in_flight_(in_flight), deadline_(deadline) {}

  bool hasRoom() const { return (int)frames_.size() < in_flight_; }
  // Room under a lower limit (interactive frames keep fewer in flight: latency, not throughput).
  bool hasRoom(int limit) const { return (int)frames_.size() < std::min(in_flight_, limit); }
  int inFlight() const { return in_flight_; }
  bool empty() const { return frames_.empty(); }
  // Issues `frame` (again, under a new epoch: its deliveries start over).
  void issue(uint64_t frame, uint32_t epoch, const FrameSpec& spec, std::set<uint32_t> renderers, std::set<uint32_t> compositors,
             Clock::time_point now);
  // Frames below `first_wanted` leave the window without being done (an interaction made them
  // stale); returns how many.
  size_t cancelBelow(uint64_t first_wanted);
  // A stage's Stats for `frame` (ignored when the frame is not in flight, or when they report
  // an earlier issue of it: a stage that finished under the old roster has not delivered
  // what the new one waits for).
  void stats(proto::Role role, uint32_t rank, uint64_t frame, uint32_t epoch);
  // The display's FrameDone: the frame and its latency in ms, or nothing if it is not in
  // flight. Only full frames set the deadline: interactive ones are cheaper by design.
  std::optional<std::pair<FrameSpec, double>> done(uint64_t frame, Clock::time_point now);

  const std::map<uint64_t, InFlight>& frames() const { return frames_; }
  // The oldest frame in flight and how long it has waited (ms), if any.
  std::optional<std::pair<uint64_t, double>> oldest(Clock::time_point now) const;
  Waiting waiting(uint64_t frame) const;
  double deadlineMs() const;
  // A typical frame time (the median latency; the deadline's start value before any).
  double typicalMs() const;
  // How long the oldest frame may wait before the master says who it waits for: several
  // frame times (before any frame completed, well inside the start deadline).
  double stallMs() const;

 private:
  int in_flight_;
  DeadlineOptions deadline_;
  std::map<uint64_t, InFlight> frames_;
  std::deque<double> latencies_;  // last kSamples, ms
};

}  // namespace tessera::master
