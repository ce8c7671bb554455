#include "master/sort_first_plan.h"

namespace tessera::master {

SortFirstPlan::SortFirstPlan(bool balance, int tiles_per_renderer)
    : balance_(balance), tiles_per_renderer_(tiles_per_renderer) {}

void SortFirstPlan::fill(proto::FrameParams& p, const Workers& w) {
  const int r = (int)w.renderers.size(), m = (int)w.compositors.size();
  if (r == 0 || m == 0) return;
  auto tiles = balance_ ? balancedTiles(p.width, p.height, r * tiles_per_renderer_, cost_.resized(p.width, p.height))
                        : equalTiles(p.width, p.height, r * tiles_per_renderer_);
  auto& work = p.work.emplace<proto::SortFirstWork>();
  std::map<uint32_t, Rect> bounds;  // compositor -> bounds of its tiles
  for (size_t i = 0; i < tiles.size(); ++i) {
    int renderer = (int)(i % r);
    const CompositorSlot& c = w.compositors[renderer % m];
    work.tiles.push_back({w.renderers[renderer], c.rank, tiles[i]});
    bounds[c.rank] = unite(bounds[c.rank], tiles[i]);
  }
  for (const CompositorSlot& c : w.compositors)
    if (bounds.count(c.rank)) p.regions.push_back({c.rank, bounds[c.rank], c.endpoint});
  frames_[p.frame] = {{}, CostGrid(p.width, p.height), work.tiles};
}

// A renderer's per-tile times, in FrameParams::tiles order; a frame's costs replace the
// model once every renderer has reported.
void SortFirstPlan::stats(const proto::StageStats& s, const Workers& w) {
  if (s.role != proto::Role::Renderer) return;
  auto it = frames_.find(s.frame);
  if (it == frames_.end()) return;
  auto& [reported, grid, tiles] = it->second;
  if (!reported.insert(s.rank).second) return;
  size_t k = 0;
  for (const auto& t : tiles)
    if (t.renderer == s.rank && k < s.tile_ms.size()) grid.add(t.tile, s.tile_ms[k++]);
  if (reported.size() >= w.renderers.size()) {
    cost_ = grid;
    frames_.erase(frames_.begin(), std::next(it));
  }
}

}  // namespace tessera::master
