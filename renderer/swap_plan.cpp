#include "renderer/swap_plan.h"

#include <algorithm>

namespace tessera::renderer {

std::optional<SwapPlan> planSwap(const proto::FrameParams& p, uint32_t me) {
  const proto::SortLastWork* work = p.sortLast();
  if (!work || work->swap.empty()) return std::nullopt;
  // Places front to back: place i draws brick order[i].
  std::vector<uint32_t> rank_at;
  int mine = -1;
  for (int b : work->order) {
    if (work->bricks[b].renderer == me) mine = (int)rank_at.size();
    rank_at.push_back(work->bricks[b].renderer);
  }
  if (mine < 0) return std::nullopt;
  auto endpointOf = [&](uint32_t rank) {
    for (const auto& s : work->swap)
      if (s.renderer == rank) return s.endpoint;
    return std::string();
  };
  SwapPlan plan;
  plan.brick = (uint32_t)work->order[mine];
  Rect part{0, 0, p.width, p.height};
  for (size_t bit = 1; bit < rank_at.size(); bit <<= 1) {
    const size_t other = (size_t)mine ^ bit;
    const bool lower = ((size_t)mine & bit) == 0;
    SwapRound r;
    r.partner = rank_at[other];
    r.endpoint = endpointOf(r.partner);
    r.keep = proto::swapHalf(part, lower);
    r.send = proto::swapHalf(part, !lower);
    r.partner_in_front = other < (size_t)mine;
    plan.rounds.push_back(std::move(r));
    part = plan.rounds.back().keep;
  }
  plan.band = part;
  return plan;
}

}  // namespace tessera::renderer
