// What a run did, for people: a progress line every few seconds while frames complete
// (frame k of N, fps, time left) and one summary line at the end (frames, wall time, fps,
// median stage times, bytes per frame between stages, losses). Fed the metrics lines.
#pragma once
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tessera::master {

class RunSummary {
 public:
  using Clock = std::chrono::steady_clock;
  // total_frames 0: interactive (no end, no estimate).
  explicit RunSummary(uint64_t total_frames, Clock::time_point start = Clock::now());

  // One frame's metrics line (Metrics::summarize plus the counters); returns a progress
  // line when one is due (the first frame, every `every`, and the last frame).
  std::optional<std::string> add(const nlohmann::json& frame, Clock::time_point done_at,
                                 std::chrono::milliseconds every = std::chrono::seconds(5));
  std::string line(Clock::time_point now = Clock::now()) const;

 private:
  double fps() const;
  std::string renderPart() const;
  uint64_t total_;
  Clock::time_point start_, first_done_, last_done_, last_progress_;
  std::vector<double> render_, composite_, display_, latency_;
  uint64_t reused_ = 0;  // frames not rendered again
  double bytes_ = 0;
  nlohmann::json last_;  // cumulative counters of the newest frame
};

}  // namespace tessera::master
