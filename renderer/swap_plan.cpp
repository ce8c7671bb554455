#include "renderer/swap_plan.h"

#include <algorithm>

#include "common/wire/swap_rule.h"

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
  const size_t places = rank_at.size();
  const Rect whole{0, 0, p.width, p.height};
  const auto slot = proto::swapSlot((size_t)mine, places);
  // Folding (proto::swapSlot): an odd place among the first 2e sends its whole image to the
  // place before it (which is in front) and is done; that place blends it in first.
  if (!slot) {
    plan.rounds.push_back({rank_at[mine - 1], endpointOf(rank_at[mine - 1]), Rect{}, whole, true});
    plan.folded = true;
    return plan;
  }
  if (mine + 1 < (int)places && !proto::swapSlot(mine + 1, places))
    plan.rounds.push_back({rank_at[mine + 1], endpointOf(rank_at[mine + 1]), whole, Rect{}, false});
  Rect part = whole;
  for (size_t bit = 1; bit < proto::swapSlots(places); bit <<= 1) {
    const size_t other = proto::swapPlaceOf(*slot ^ bit, places);
    const bool lower = (*slot & bit) == 0;
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
