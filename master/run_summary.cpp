#include "master/run_summary.h"

#include <algorithm>

#include <fmt/format.h>

namespace tessera::master {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double seconds(RunSummary::Clock::duration d) { return std::chrono::duration<double>(d).count(); }

uint64_t counter(const nlohmann::json& j, const char* key) {
  return j.contains(key) ? (uint64_t)j[key].get<double>() : 0;
}

}  // namespace

RunSummary::RunSummary(uint64_t total_frames, Clock::time_point start) : total_(total_frames), start_(start) {}

double RunSummary::fps() const {
  const size_t n = latency_.size();
  const double span = seconds(last_done_ - first_done_);
  return n > 1 && span > 0 ? (double)(n - 1) / span : 0;
}

std::optional<std::string> RunSummary::add(const nlohmann::json& j, Clock::time_point done_at,
                                           std::chrono::milliseconds every) {
  if (latency_.empty()) first_done_ = done_at;
  last_done_ = done_at;
  if (j.contains("render_ms_max")) render_.push_back(j["render_ms_max"].get<double>());
  else ++reused_;  // not rendered again: no render time to take the median of
  composite_.push_back(j.value("composite_ms_max", 0.0));
  display_.push_back(j.value("display_ms", 0.0));
  latency_.push_back(j.value("latency_ms", 0.0));
  bytes_ += j.value("render_bytes_encoded", 0.0) + j.value("composite_bytes_encoded", 0.0);
  last_ = j;
  const uint64_t n = latency_.size();
  const bool last = total_ > 0 && n >= total_;
  if (n > 1 && !last && done_at - last_progress_ < every) return std::nullopt;
  last_progress_ = done_at;
  if (total_ == 0) return fmt::format("frame {} done, {:.2f} fps", n, fps());
  const double rate = fps();
  const std::string left = rate > 0 && !last ? fmt::format(", about {:.0f} s left", (double)(total_ - n) / rate) : "";
  return fmt::format("frame {} of {} ({:.0f}%), {:.2f} fps{}", n, total_, 100.0 * (double)n / (double)total_, rate, left);
}

// "240 ms", "240 ms (9 of 10 frames reused the image: the view did not change)".
std::string RunSummary::renderPart() const {
  std::string s = render_.empty() ? "none" : fmt::format("{:.0f} ms", median(render_));
  if (reused_ > 0)
    s += fmt::format(" ({} of {} frames reused the image: the view did not change)", reused_, latency_.size());
  return s;
}

std::string RunSummary::line(Clock::time_point now) const {
  const size_t n = latency_.size();
  const uint64_t dropped = counter(last_, "master_dropped") + counter(last_, "render_dropped") +
                           counter(last_, "composite_dropped") + counter(last_, "display_dropped");
  return fmt::format(
      "run summary: {} frames in {:.1f} s, {}; median per frame: render {}, composite {:.1f} ms, "
      "display {:.0f} ms, latency {:.0f} ms; {:.2f} MB per frame between stages; dropped {} messages, "
      "{} strips rejected, {} stages reassigned",
      n, seconds(now - start_), n > 1 ? fmt::format("{:.2f} fps", fps()) : std::string("no rate from one frame"), renderPart(), median(composite_), median(display_), median(latency_),
      n ? bytes_ / (double)n / 1e6 : 0.0, dropped, counter(last_, "strips_rejected"), counter(last_, "reassignments"));
}

}  // namespace tessera::master
