// The frames an interaction cancelled (FrameParams::first_wanted moved past them): their
// parts may still be on their way, and are discarded quietly rather than counted as faults.
// A fast drag cancels again before the last cancel's parts have all arrived, so the latest
// few ranges are kept, not only the newest one. Bounded: a part of a range this old has had
// many frame times to arrive.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>

namespace tessera {

class CancelledFrames {
 public:
  // Frames [lo, hi) will never be shown.
  void add(uint64_t lo, uint64_t hi) {
    if (lo >= hi) return;
    ranges_.emplace_back(lo, hi);
    if (ranges_.size() > kKept) ranges_.pop_front();
  }
  bool contains(uint64_t frame) const {
    for (const auto& [lo, hi] : ranges_)
      if (frame >= lo && frame < hi) return true;
    return false;
  }

 private:
  static constexpr size_t kKept = 16;
  std::deque<std::pair<uint64_t, uint64_t>> ranges_;
};

}  // namespace tessera
