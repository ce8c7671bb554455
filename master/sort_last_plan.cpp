#include "master/sort_last_plan.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "master/balance.h"

namespace tessera::master {

SortLastPlan::SortLastPlan(VolumeSummary volume, const TransferFunction& tf, int width, int height, bool balance)
    : volume_(std::move(volume)), tf_(tf), width_(width), height_(height), balance_(balance) {
  // Said once, by the master: a range that misses the data makes every frame empty or uniform.
  if (std::string why = rangeProblem(volume_.shape); !why.empty()) spdlog::warn("volume: {}", why);
}

void SortLastPlan::reassign(const Workers& w) {
  tree_ = splitBricks(volume_, std::max<int>(1, (int)w.renderers.size()), tf_);
}

void SortLastPlan::fill(proto::FrameParams& p, const Workers& w) {
  auto& work = p.work.emplace<proto::SortLastWork>();
  for (size_t i = 0; i < tree_.bricks.size() && i < w.renderers.size(); ++i)
    work.bricks.push_back({w.renderers[i], tree_.bricks[i]});
  work.order = tree_.visibilityOrder(volume_.shape, p.camera);
  auto bands = balancedBands(width_, height_, (int)w.compositors.size(), balance_ ? last_active_ : std::vector<Rect>{});
  for (size_t i = 0; i < bands.size(); ++i)
    p.regions.push_back({w.compositors[i].rank, bands[i], w.compositors[i].endpoint});
}

void SortLastPlan::stats(const proto::StageStats& s, const Workers&) {
  if (s.role != proto::Role::Renderer || s.frame + 1 < latest_active_frame_) return;
  if (s.frame + 1 > latest_active_frame_) last_active_.clear();
  latest_active_frame_ = s.frame + 1;
  last_active_.push_back(s.active);
}

}  // namespace tessera::master
