#include "renderer/swap_plan.h"

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
  Rect part{0, 0, p.width, p.height};
  size_t stride = 1;  // the place value of this round's digit
  for (size_t k : proto::swapRadices(rank_at.size())) {
    const size_t digit = ((size_t)mine / stride) % k;
    SwapRound r;
    r.keep = proto::swapPart(part, k, digit);
    for (size_t i = 0; i < k; ++i) {
      if (i == digit) continue;
      const uint32_t rank = rank_at[(size_t)mine + (i * stride) - (digit * stride)];
      r.partners.push_back({rank, endpointOf(rank), proto::swapPart(part, k, i), (int)i - (int)digit});
    }
    part = r.keep;
    plan.rounds.push_back(std::move(r));
    stride *= k;
  }
  plan.band = part;
  return plan;
}

}  // namespace tessera::renderer
