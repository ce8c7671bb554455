#include "gather.h"

#include <utility>

namespace tessera::compositor {

std::string Gather::check(const proto::FrameParams& p, const proto::Piece& piece) const {
  if (piece.epoch != p.epoch) return "piece epoch differs from FrameParams";
  if (piece.brick >= p.bricks.size())
    return "piece for brick " + std::to_string(piece.brick) + " of " + std::to_string(p.bricks.size());
  if (p.bricks[piece.brick].renderer != piece.renderer) return "piece from a renderer not assigned that brick";
  if (piece.format != p.format) return "piece pixel format differs from FrameParams";
  for (const auto& reg : p.regions)
    if (reg.compositor == rank_ && reg.region != piece.region) return "piece cut for another region";
  return "";
}

std::vector<std::string> Gather::takeLateDrops() { return std::exchange(late_drops_, {}); }

std::string Gather::addParams(proto::FrameParams p) {
  if (p.epoch < epoch_) return "FrameParams of an older epoch";
  if (p.epoch > epoch_) {  // membership changed: everything of older epochs is stale
    epoch_ = p.epoch;
    for (auto it = frames_.begin(); it != frames_.end();) {
      if (it->second.params && it->second.params->epoch < epoch_) {
        it = frames_.erase(it);
        continue;
      }
      std::erase_if(it->second.pieces, [&](const auto& kv) { return kv.second.epoch < epoch_; });
      ++it;
    }
    if (p.frame < next_expected_) next_expected_ = p.frame;  // frames in flight are issued again
  }
  if (p.frame < next_expected_) return "FrameParams for a finished frame";
  Frame& f = frames_[p.frame];
  f.params = std::move(p);
  for (auto it = f.pieces.begin(); it != f.pieces.end();) {  // pieces that came first
    std::string why = check(*f.params, it->second);
    if (why.empty()) {
      ++it;
      continue;
    }
    late_drops_.push_back(why);
    it = f.pieces.erase(it);
  }
  while (frames_.size() > kMaxPending) frames_.erase(frames_.begin());
  return "";
}

std::string Gather::addPiece(proto::Piece piece) {
  if (piece.epoch < epoch_) return "piece of an older epoch";
  if (piece.frame < next_expected_ && piece.epoch == epoch_) return "piece for a finished frame";
  Frame& f = frames_[piece.frame];
  if (f.params) {
    std::string why = check(*f.params, piece);
    if (!why.empty()) return why;
  }
  if (f.pieces.count(piece.brick)) return "duplicate piece for brick " + std::to_string(piece.brick);
  f.pieces.emplace(piece.brick, std::move(piece));
  while (frames_.size() > kMaxPending) frames_.erase(frames_.begin());
  return "";
}

std::optional<Gather::Ready> Gather::pop() {
  for (auto it = frames_.begin(); it != frames_.end(); ++it) {
    Frame& f = it->second;
    if (!f.params || f.pieces.size() != f.params->bricks.size()) continue;
    Ready r;
    r.params = std::move(*f.params);
    for (const auto& reg : r.params.regions)
      if (reg.compositor == rank_) r.region = reg.region;
    for (auto& [brick, piece] : f.pieces) r.pieces.push_back(std::move(piece));
    next_expected_ = it->first + 1;
    frames_.erase(frames_.begin(), std::next(it));  // older incomplete frames can never finish now
    return r;
  }
  return std::nullopt;
}

}  // namespace tessera::compositor
