// Per-frame metrics of the farm, written as one JSON line per frame: per-stage times,
// bytes raw and compressed, active pixels, imbalance, latency, dropped messages, and the
// master's fault counters so far (reassignments, re-issued frames, refused peers).
// A frame's line is written once its FrameDone and every stage's stats are in (or a
// grace period has passed, since stats and FrameDone travel on different paths).
#pragma once
#include <chrono>
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/wire/protocol.h"
#include "master/refinement.h"
#include "master/run_summary.h"

namespace tessera::master {

class Metrics {
 public:
  // path "" = log only; total_frames 0 = interactive (progress without an estimate).
  explicit Metrics(const std::string& path, uint64_t total_frames = 0);
  // A failed start (no line written) leaves an existing file as it was and removes one it created.
  ~Metrics();
  Metrics(const Metrics&) = delete;
  Metrics& operator=(const Metrics&) = delete;

  void issued(uint64_t frame, uint32_t epoch, int renderers, int compositors, const FrameSpec& spec);
  // A frame an interaction made stale: no line, counted in cancelled_frames.
  void cancelled(uint64_t frame);
  void stats(const proto::StageStats& s);
  void done(const proto::FrameDone& d, double latency_ms, uint64_t master_dropped);
  void flushOlderThan(std::chrono::steady_clock::time_point t);
  void flushAll();
  uint64_t framesDone() const { return frames_done_; }
  std::string runSummary() const { return run_.line(); }
  size_t pending() const { return frames_.size(); }  // frames whose line is not written yet

  // Cumulative fault counters, written on every line.
  void reassigned() { ++reassignments_; }
  void reissued(uint64_t frames) { reissued_ += frames; }
  void refused() { ++refused_; }
  uint64_t reassignments() const { return reassignments_; }
  uint64_t reissuedFrames() const { return reissued_; }
  uint64_t refusedPeers() const { return refused_; }

  // Frames whose renderers showed different steps (some could not read the step asked for),
  // since the last call.
  struct MixedSteps {
    uint64_t frame = 0;
    int asked = 0;
    std::set<uint32_t> shown;
  };
  std::vector<MixedSteps> takeMixedSteps() { return std::exchange(mixed_, {}); }

  // The JSON object of one frame (exposed for tests).
  static nlohmann::json summarize(const std::vector<proto::StageStats>& renderers,
                                  const std::vector<proto::StageStats>& compositors, const proto::FrameDone& done,
                                  double latency_ms);

 private:
  struct Frame {
    uint32_t epoch = 0;
    int renderers = 0, compositors = 0;
    FrameSpec spec;
    std::vector<proto::StageStats> r, c;
    bool done = false;
    proto::FrameDone d;
    double latency_ms = 0;
    uint64_t master_dropped = 0;
    std::chrono::steady_clock::time_point done_at;
  };
  void write(uint64_t frame, Frame& f);

  std::ofstream out_;
  std::string path_;
  bool wrote_ = false, warned_empty_ = false, existed_ = false;
  std::map<uint64_t, Frame> frames_;
  uint64_t frames_done_ = 0;
  uint64_t reassignments_ = 0, reissued_ = 0, refused_ = 0, cancelled_ = 0;
  std::vector<MixedSteps> mixed_;
  bool interactive_run_ = false;  // lines say what each frame showed (camera, size, level of detail)
  std::chrono::steady_clock::time_point start_;
  RunSummary run_;
};

}  // namespace tessera::master
