#include "display/assembly.h"

#include <algorithm>

#include <fmt/format.h>

#include "common/wire/swap_rule.h"

namespace tessera::display {
namespace {

std::string checkMember(const proto::FrameParams& p, const Assembly::Source& from, const proto::Strips& s) {
  if (s.epoch != p.epoch) return "strips epoch differs from FrameParams";
  for (const auto& src : Assembly::sourcesOf(p))
    if (src == from) return "";
  return fmt::format("strips from {} {} that {}", proto::roleName(from.role), from.rank,
                     from.role == proto::Role::Renderer ? "has no band in the frame (not a binary-swap frame of it)"
                                                       : "has no region in the frame");
}

}  // namespace

Rect Assembly::areaOf(const proto::FrameParams& p, const Source& s) {
  if (s.role == proto::Role::Renderer) return proto::swapBand(p, s.rank).value_or(Rect{});
  for (const auto& r : p.regions)
    if (r.compositor == s.rank) return r.region;
  return {};
}

std::vector<Assembly::Source> Assembly::sourcesOf(const proto::FrameParams& p) {
  std::vector<Source> out;
  if (const auto* work = p.sortLast(); work && !work->swap.empty()) {
    for (const auto& peer : work->swap)  // one whose band has no rows (fewer rows than bands) sends none
      if (proto::swapBand(p, peer.renderer)) out.push_back({proto::Role::Renderer, peer.renderer});
    return out;
  }
  for (const auto& r : p.regions) out.push_back({proto::Role::Compositor, r.compositor});
  return out;
}

void Assembly::addParams(proto::FrameParams p) {
  if (p.epoch < epoch_) return;  // stale: its frames were issued again
  if (p.epoch > epoch_) {        // frames in flight were issued again: forget their old strips
    epoch_ = p.epoch;
    for (auto& [f, frame] : frames_) std::erase_if(frame.strips, [&](auto& kv) { return kv.second.epoch < epoch_; });
  }
  if (p.first_wanted > next_) {  // an interaction made the frames before it stale: never shown
    frames_.erase(frames_.begin(), frames_.lower_bound(p.first_wanted));
    cancelled_.add(next_, p.first_wanted);
    next_ = p.first_wanted;
  }
  if (p.frame < next_) return;
  if (!newest_ || p.epoch > newest_->epoch || p.frame > newest_->frame) newest_ = p;
  Frame& frame = frames_[p.frame];
  frame.params = std::move(p);
  for (auto it = frame.strips.begin(); it != frame.strips.end();) {  // strips that came first
    std::string why = checkMember(*frame.params, it->first, it->second);
    if (!why.empty()) late_drops_.emplace_back(it->first.rank, why);
    it = why.empty() ? std::next(it) : frame.strips.erase(it);
  }
  for (auto it = frames_.upper_bound(newest_->frame + kAheadWithoutParams); it != frames_.end();)
    it = it->second.params ? std::next(it) : dropWaiting(it, "strips waited too far ahead of the newest FrameParams");
}

std::string Assembly::addStrips(Source from, proto::Strips s, size_t bytes) {
  if (s.epoch < epoch_) return "";  // stale, not malformed
  if (cancelled_.contains(s.frame)) return "";
  if (s.frame < next_) return "strips for a frame already shown";
  auto it = frames_.find(s.frame);
  if (it != frames_.end()) {
    auto held = it->second.strips.find(from);
    if (held != it->second.strips.end()) {
      if (held->second.epoch == s.epoch) return "duplicate strips";
      if (held->second.epoch > s.epoch) return "strips of an older epoch than the ones held";
      it->second.strips.erase(held);  // a newer epoch's strips may beat its FrameParams
    }
  }
  const bool described = it != frames_.end() && it->second.params && it->second.params->epoch == s.epoch;
  std::string why = described ? checkMember(*it->second.params, from, s) : admitWaiting(from, s);
  if (!why.empty()) return why;
  Frame& frame = frames_[s.frame];
  frame.sizes[from] = bytes;
  frame.strips.emplace(from, std::move(s));
  return "";
}

std::string Assembly::admitWaiting(const Source& from, const proto::Strips& s) {
  if (newest_ && s.frame > newest_->frame + kAheadWithoutParams) return "strips for a frame too far ahead";
  if (newest_ && s.epoch == newest_->epoch) {
    if (auto why = checkMember(*newest_, from, s); !why.empty()) return why + " (waiting for its FrameParams)";
  }
  size_t held = waitingBytes();
  while (held + s.stream.size() > waiting_budget_) {
    auto far = frames_.end();
    for (auto it = frames_.upper_bound(s.frame); it != frames_.end(); ++it)
      if (!it->second.params) far = it;
    if (far == frames_.end()) return "strips waiting for FrameParams would exceed the budget";
    for (const auto& [c, st] : far->second.strips) held -= st.stream.size();
    dropWaiting(far, "strips evicted while waiting for FrameParams: a nearer frame needed the room");
  }
  return "";
}

size_t Assembly::waitingBytes() const {
  size_t n = 0;
  for (const auto& [f, frame] : frames_)
    if (!frame.params)
      for (const auto& [c, st] : frame.strips) n += st.stream.size();
  return n;
}

std::map<uint64_t, Assembly::Frame>::iterator Assembly::dropWaiting(std::map<uint64_t, Frame>::iterator it,
                                                                    const std::string& why) {
  for (const auto& [src, st] : it->second.strips) late_drops_.emplace_back(src.rank, "frame " + std::to_string(it->first) + ": " + why);
  return frames_.erase(it);
}

std::optional<std::pair<uint64_t, Assembly::Source>> Assembly::awaited() const {
  auto it = frames_.find(next_);
  if (it == frames_.end() || !it->second.params) return std::nullopt;
  const Frame& f = it->second;
  for (const auto& src : sourcesOf(*f.params)) {
    auto s = f.strips.find(src);
    if (s == f.strips.end() || s->second.epoch != f.params->epoch) return std::make_pair(next_, src);
  }
  return std::nullopt;
}

bool Assembly::complete(const Frame& f) const {
  if (!f.params) return false;
  for (const auto& src : sourcesOf(*f.params)) {
    auto it = f.strips.find(src);
    if (it == f.strips.end() || it->second.epoch != f.params->epoch) return false;  // newer: its FrameParams come
  }
  return true;
}

std::optional<Assembly::Frame> Assembly::popNext() {
  auto it = frames_.find(next_);
  if (it == frames_.end() || !complete(it->second)) return std::nullopt;
  Frame f = std::move(it->second);
  frames_.erase(it);
  ++next_;
  // Strips of a newer issue of the frame from senders it does not name (they waited for their
  // FrameParams, which will now never be used) are not part of it.
  const auto sources = sourcesOf(*f.params);
  for (auto s = f.strips.begin(); s != f.strips.end();) {
    const bool named = std::find(sources.begin(), sources.end(), s->first) != sources.end();
    if (named && s->second.epoch == f.params->epoch) {
      f.bytes += f.sizes[s->first];
      ++s;
      continue;
    }
    late_drops_.emplace_back(s->first.rank, "strips of another issue of frame " + std::to_string(f.params->frame) +
                                                " from a sender it does not name");
    s = f.strips.erase(s);
  }
  return f;
}

bool Assembly::nextHasParams() const {
  auto it = frames_.find(next_);
  return it != frames_.end() && it->second.params;
}

}  // namespace tessera::display
