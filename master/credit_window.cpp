#include "master/credit_window.h"

#include <algorithm>

namespace tessera::master {

void CreditWindow::issue(uint64_t frame, uint32_t epoch, const FrameSpec& spec, std::set<uint32_t> renderers,
                         std::set<uint32_t> compositors, Clock::time_point now) {
  frames_[frame] = InFlight{now, epoch, spec, std::move(renderers), std::move(compositors), {}, {}};
}

size_t CreditWindow::cancelBelow(uint64_t first_wanted) {
  const auto end = frames_.lower_bound(first_wanted);
  const size_t n = (size_t)std::distance(frames_.begin(), end);
  frames_.erase(frames_.begin(), end);
  return n;
}

void CreditWindow::stats(proto::Role role, uint32_t rank, uint64_t frame, uint32_t epoch) {
  auto it = frames_.find(frame);
  if (it == frames_.end() || it->second.epoch != epoch) return;
  if (role == proto::Role::Renderer) it->second.renderers_in.insert(rank);
  if (role == proto::Role::Compositor) it->second.compositors_in.insert(rank);
}

std::optional<std::pair<FrameSpec, double>> CreditWindow::done(uint64_t frame, Clock::time_point now) {
  auto it = frames_.find(frame);
  if (it == frames_.end()) return std::nullopt;
  double ms = std::chrono::duration<double, std::milli>(now - it->second.issued).count();
  FrameSpec spec = std::move(it->second.spec);
  frames_.erase(it);
  if (!spec.interactive) latencies_.push_back(ms);
  if (latencies_.size() > kSamples) latencies_.pop_front();
  return std::make_pair(std::move(spec), ms);
}

std::optional<std::pair<uint64_t, double>> CreditWindow::oldest(Clock::time_point now) const {
  if (frames_.empty()) return std::nullopt;
  // Re-issued frames restart their clock: the one issued longest ago is the most overdue.
  auto it = std::min_element(frames_.begin(), frames_.end(),
                             [](const auto& a, const auto& b) { return a.second.issued < b.second.issued; });
  return std::make_pair(it->first, std::chrono::duration<double, std::milli>(now - it->second.issued).count());
}

CreditWindow::Waiting CreditWindow::waiting(uint64_t frame) const {
  Waiting w;
  auto it = frames_.find(frame);
  if (it == frames_.end()) return w;
  const InFlight& f = it->second;
  for (uint32_t r : f.renderers)
    if (!f.renderers_in.count(r)) w.renderers.push_back(r);
  for (uint32_t c : f.compositors)
    if (!f.compositors_in.count(c)) w.compositors.push_back(c);
  w.display = w.renderers.empty() && w.compositors.empty();
  if (f.compositors.empty()) w.display_sources = proto::Role::Renderer;
  return w;
}

double CreditWindow::typicalMs() const {
  if (latencies_.empty()) return deadline_.start_s * 1000;
  std::vector<double> v(latencies_.begin(), latencies_.end());
  std::nth_element(v.begin(), v.begin() + (long)v.size() / 2, v.end());
  return v[v.size() / 2];
}

double CreditWindow::stallMs() const {
  if (latencies_.empty()) return std::min(2000.0, deadlineMs() / 2);
  return std::max(1000.0, 3 * typicalMs());
}

double CreditWindow::deadlineMs() const {
  if (latencies_.empty()) return deadline_.start_s * 1000;
  return std::max(deadline_.floor_s * 1000, deadline_.factor * typicalMs());
}

}  // namespace tessera::master
