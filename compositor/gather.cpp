#include "compositor/gather.h"

#include <algorithm>
#include <utility>

namespace tessera::compositor {
namespace {

template <class Frame>
size_t partBytes(const Frame& f) {
  size_t n = 0;
  for (const auto& [key, piece] : f.pieces) n += piece.pixels.size();
  for (const auto& [key, fb] : f.framebuffers) n += fb.pixels.size();
  return n;
}

bool allOfEpoch(const auto& f, uint32_t epoch) {
  auto same = [&](const auto& kv) { return kv.second.epoch == epoch; };
  return std::all_of(f.pieces.begin(), f.pieces.end(), same) &&
         std::all_of(f.framebuffers.begin(), f.framebuffers.end(), same);
}

}  // namespace

std::string Gather::check(const proto::FrameParams& p, const proto::Piece& piece) const {
  if (piece.epoch != p.epoch) return "piece epoch differs from FrameParams";
  const proto::SortLastWork* work = p.sortLast();
  if (!work) return "sort-last piece for a sort-first frame";
  if (piece.brick >= work->bricks.size())
    return "piece for brick " + std::to_string(piece.brick) + " of " + std::to_string(work->bricks.size());
  if (work->bricks[piece.brick].renderer != piece.renderer) return "piece from a renderer not assigned that brick";
  if (!work->swap.empty()) return "piece for a binary-swap frame (its bands go to the display)";
  if (piece.format != p.format) return "piece pixel format differs from FrameParams";
  for (const auto& reg : p.regions)
    if (reg.compositor == rank_ && reg.region != piece.region) return "piece cut for another region";
  return "";
}

std::string Gather::check(const proto::FrameParams& p, const proto::Framebuffer& fb) const {
  if (fb.epoch != p.epoch) return "framebuffer epoch differs from FrameParams";
  if (!routedRenderers(p).count(fb.renderer))
    return "framebuffer from renderer " + std::to_string(fb.renderer) + " whose tiles are not routed here";
  return "";
}

// Membership of a waiting part is known only when it belongs to the newest FrameParams'
// epoch; a newer epoch's parts may name members that are not known yet.
std::string Gather::checkWaiting(const proto::Piece& piece) const {
  if (newest_ && piece.epoch == newest_->epoch && piece.brick >= newest_->bricks)
    return "piece waiting for FrameParams names brick " + std::to_string(piece.brick) + " of " +
           std::to_string(newest_->bricks);
  return "";
}

std::string Gather::checkWaiting(const proto::Framebuffer& fb) const {
  if (newest_ && fb.epoch == newest_->epoch && !newest_->routed.count(fb.renderer))
    return "framebuffer waiting for FrameParams from renderer " + std::to_string(fb.renderer) +
           " whose tiles are not routed here";
  return "";
}

// Makes room for `bytes` of a part of `frame` that waits for its FrameParams, evicting
// the farthest waiting frames beyond it; "" when admitted.
std::string Gather::admitWaiting(uint64_t frame, size_t bytes) {
  if (newest_ && frame > newest_->frame + kAheadWithoutParams)
    return "part for frame " + std::to_string(frame) + " too far ahead of the newest FrameParams frame=" +
           std::to_string(newest_->frame);
  size_t held = waitingBytes();
  while (held + bytes > waiting_budget_) {
    auto far = frames_.end();
    for (auto it = frames_.upper_bound(frame); it != frames_.end(); ++it)
      if (!it->second.params) far = it;
    if (far == frames_.end())
      return "parts waiting for FrameParams would exceed the budget of " + std::to_string(waiting_budget_) + " bytes";
    held -= partBytes(far->second);
    dropWaiting(far, "evicted while waiting for FrameParams: a nearer frame needed the room");
  }
  return "";
}

void Gather::dropWaiting(std::map<uint64_t, Frame>::iterator it, const std::string& why) {
  const size_t parts = it->second.pieces.size() + it->second.framebuffers.size();
  for (size_t i = 0; i < parts; ++i) late_drops_.push_back("frame " + std::to_string(it->first) + ": " + why);
  frames_.erase(it);
}

size_t Gather::waitingBytes() const {
  size_t n = 0;
  for (const auto& [frame, f] : frames_) {
    if (!f.params) {
      n += partBytes(f);
      continue;
    }
    // A newer epoch's part beside older FrameParams waits for its own, within the same budget
    // (else a part of an epoch that never comes, repeated per brick, held memory unbounded).
    for (const auto& [key, piece] : f.pieces) n += piece.epoch != f.params->epoch ? piece.pixels.size() : 0;
    for (const auto& [key, fb] : f.framebuffers) n += fb.epoch != f.params->epoch ? fb.pixels.size() : 0;
  }
  return n;
}

std::set<uint32_t> Gather::routedRenderers(const proto::FrameParams& p) const {
  std::set<uint32_t> r;
  if (const proto::SortFirstWork* work = p.sortFirst())
    for (const auto& t : work->tiles)
      if (t.compositor == rank_) r.insert(t.renderer);
  return r;
}

std::vector<std::string> Gather::takeLateDrops() { return std::exchange(late_drops_, {}); }

std::string Gather::addParams(proto::FrameParams p) {
  if (p.epoch < epoch_) return "FrameParams of an older epoch";
  if (p.epoch > epoch_) {  // membership changed: everything of older epochs is stale
    epoch_ = p.epoch;
    for (auto it = frames_.begin(); it != frames_.end();) {  // parts of the new epoch may be here already
      if (it->second.params && it->second.params->epoch < epoch_) it->second.params.reset();
      std::erase_if(it->second.pieces, [&](const auto& kv) { return kv.second.epoch < epoch_; });
      std::erase_if(it->second.framebuffers, [&](const auto& kv) { return kv.second.epoch < epoch_; });
      it = it->second.params || !it->second.pieces.empty() || !it->second.framebuffers.empty() ? std::next(it)
                                                                                              : frames_.erase(it);
    }
    if (p.frame < next_expected_) next_expected_ = p.frame;  // frames in flight are issued again
  }
  if (p.first_wanted > next_expected_ && p.epoch == epoch_) {  // an interaction cancelled the frames before it
    cancelled_.add(next_expected_, p.first_wanted);
    frames_.erase(frames_.begin(), frames_.lower_bound(p.first_wanted));
    next_expected_ = p.first_wanted;
  }
  if (p.frame < next_expected_) return "FrameParams for a finished frame";
  if (!newest_ || p.epoch > newest_->epoch || p.frame > newest_->frame)
    newest_ = Membership{p.frame, p.epoch, p.sortLast() ? p.sortLast()->bricks.size() : 0, routedRenderers(p)};
  Frame& f = frames_[p.frame];
  f.params = std::move(p);
  auto recheck = [&](auto& parts) {  // parts that came before their parameters
    for (auto it = parts.begin(); it != parts.end();) {
      std::string why = check(*f.params, it->second);
      if (why.empty()) {
        ++it;
        continue;
      }
      late_drops_.push_back(why);
      it = parts.erase(it);
    }
  };
  recheck(f.pieces);
  recheck(f.framebuffers);
  for (auto it = frames_.upper_bound(newest_->frame + kAheadWithoutParams); it != frames_.end();) {
    auto next = std::next(it);
    if (!it->second.params) dropWaiting(it, "waited too far ahead of the newest FrameParams");
    it = next;
  }
  return "";
}

template <class Part>
std::string Gather::add(Part part, uint32_t key, std::map<uint32_t, Part> Frame::*parts, const char* what) {
  if (part.epoch < epoch_) return std::string(what) + " of an older epoch";
  if (cancelled_.contains(part.frame)) return "";  // cancelled: discarded
  if (part.frame < next_expected_ && part.epoch == epoch_) return std::string(what) + " for a finished frame";
  auto it = frames_.find(part.frame);
  if (it != frames_.end()) {
    auto held = (it->second.*parts).find(key);
    if (held != (it->second.*parts).end()) {
      if (held->second.epoch == part.epoch) return std::string("duplicate ") + what + " " + std::to_string(key);
      if (held->second.epoch > part.epoch) return std::string(what) + " of an older epoch than the one held";
      // A newer epoch's part may come before its FrameParams: the held one is stale.
      (it->second.*parts).erase(held);
    }
  }
  std::string why;
  if (it != frames_.end() && it->second.params && it->second.params->epoch == part.epoch) {
    why = check(*it->second.params, part);
  } else {
    why = checkWaiting(part);
    if (why.empty()) why = admitWaiting(part.frame, part.pixels.size());  // may evict farther frames
  }
  if (!why.empty()) return why;
  (frames_[part.frame].*parts).emplace(key, std::move(part));
  return "";
}

std::string Gather::addPiece(proto::Piece piece) {
  uint32_t key = piece.brick;
  return add(std::move(piece), key, &Frame::pieces, "piece");
}

std::string Gather::addFramebuffer(proto::Framebuffer fb) {
  uint32_t key = fb.renderer;
  return add(std::move(fb), key, &Frame::framebuffers, "framebuffer");
}

std::optional<std::pair<uint64_t, uint32_t>> Gather::awaited() const {
  for (const auto& [frame, f] : frames_) {
    if (!f.params) continue;
    // A part of a newer epoch holds the frame until that epoch's FrameParams come, at once when
    // it raced them: if they never come, its sender is the one to name (not this compositor).
    if (!allOfEpoch(f, f.params->epoch)) {
      for (const auto& [brick, piece] : f.pieces)
        if (piece.epoch != f.params->epoch) return std::make_pair(frame, piece.renderer);
      for (const auto& [renderer, fb] : f.framebuffers)
        if (fb.epoch != f.params->epoch) return std::make_pair(frame, fb.renderer);
    }
    if (const proto::SortLastWork* work = f.params->sortLast()) {
      const bool mine = std::any_of(f.params->regions.begin(), f.params->regions.end(),
                                    [&](const auto& reg) { return reg.compositor == rank_; });
      for (uint32_t b = 0; mine && b < work->bricks.size(); ++b)
        if (!f.pieces.count(b)) return std::make_pair(frame, work->bricks[b].renderer);
    } else {
      for (uint32_t r : routedRenderers(*f.params))
        if (!f.framebuffers.count(r)) return std::make_pair(frame, r);
    }
  }
  return std::nullopt;
}

std::optional<Gather::Ready> Gather::pop() {
  for (auto it = frames_.begin(); it != frames_.end(); ++it) {
    Frame& f = it->second;
    if (!f.params || !allOfEpoch(f, f.params->epoch)) continue;  // newer parts: newer FrameParams are coming
    const proto::SortLastWork* sort_last = f.params->sortLast();
    // A sort-last frame without a region of ours (a binary swap's) has nothing to wait for.
    const bool mine = std::any_of(f.params->regions.begin(), f.params->regions.end(),
                                  [&](const auto& reg) { return reg.compositor == rank_; });
    if (sort_last ? mine && f.pieces.size() != sort_last->bricks.size()
                  : f.framebuffers.size() != routedRenderers(*f.params).size())
      continue;
    Ready r;
    r.params = std::move(*f.params);
    for (const auto& reg : r.params.regions)
      if (reg.compositor == rank_) r.region = reg.region;
    if (const proto::SortFirstWork* work = r.params.sortFirst())
      for (const auto& t : work->tiles)
        if (t.compositor == rank_) r.tiles.push_back(t.tile);
    for (auto& [brick, piece] : f.pieces) r.pieces.push_back(std::move(piece));
    for (auto& [renderer, fb] : f.framebuffers) r.framebuffers.push_back(std::move(fb));
    next_expected_ = it->first + 1;
    // Older incomplete frames can never finish now; their waiting parts count as drops.
    for (auto old = frames_.begin(); old != it;) {
      auto next = std::next(old);
      if (!old->second.params) dropWaiting(old, "its FrameParams never came");
      old = next;
    }
    frames_.erase(frames_.begin(), std::next(it));
    return r;
  }
  return std::nullopt;
}

}  // namespace tessera::compositor
