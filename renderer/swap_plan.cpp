#include "renderer/swap_plan.h"

#include <algorithm>
#include <cstring>

#include "common/wire/pixels.h"

namespace tessera::renderer {
namespace {

Rect half(const Rect& r, bool upper) {
  const int top = r.h / 2;
  return upper ? Rect{r.x, r.y, r.w, top} : Rect{r.x, r.y + top, r.w, r.h - top};
}

Rect local(const Rect& r, const Rect& origin) { return {r.x - origin.x, r.y - origin.y, r.w, r.h}; }

}  // namespace

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
    r.keep = half(part, lower);
    r.send = half(part, !lower);
    r.partner_in_front = other < (size_t)mine;
    plan.rounds.push_back(std::move(r));
    part = plan.rounds.back().keep;
  }
  plan.band = part;
  return plan;
}

void packView(const LayerView& v, proto::PixelFormat f, std::vector<std::byte>& out) {
  if (v.rect.empty()) return out.clear();
  packPixels(*v.img, local(v.rect, v.covers), f, out);
}

Layer blendLayer(const LayerView& mine, std::span<const std::byte> pixels, const Rect& theirs, proto::PixelFormat f,
                 bool partner_in_front, std::vector<float>&& storage) {
  Layer out;
  out.rect = unite(mine.rect, theirs);
  if (out.rect.empty()) return out;
  out.img = ImageF(out.rect.w, out.rect.h, std::move(storage));
  const Rect at = local(mine.rect, out.rect);
  auto row = [&](int y) { return mine.img->at(mine.rect.x - mine.covers.x, mine.rect.y - mine.covers.y + y); };
  if (!partner_in_front) {  // mine first, theirs under it
    for (int y = 0; y < at.h; ++y) std::memcpy(out.img.at(at.x, at.y + y), row(y), sizeof(float) * 4 * at.w);
    if (!theirs.empty()) compositeUnder(out.img, out.rect, pixels, theirs, f);
    return out;
  }
  if (!theirs.empty()) compositeUnder(out.img, out.rect, pixels, theirs, f);  // onto transparent black: theirs exactly
  for (int y = 0; y < at.h; ++y) {  // then mine under it, as the compositors blend
    float* d = out.img.at(at.x, at.y + y);
    const float* s = row(y);
    for (int x = 0; x < 4 * at.w; x += 4) {
      const float t = 1.0f - d[x + 3];
      for (int c = 0; c < 4; ++c) d[x + c] += t * s[x + c];
    }
  }
  return out;
}

}  // namespace tessera::renderer
