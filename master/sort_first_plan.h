// Sort-first work: the screen cut into renderers x tiles_per_renderer tiles (equal, or
// balanced by the per-tile render cost of the last fully reported frame), dealt round
// robin to renderers; renderer i's tiles are routed by compositor i mod M, so each
// renderer sends one framebuffer.
#pragma once
#include <map>
#include <set>

#include "master/plan.h"
#include "master/tiling.h"

namespace tessera::master {

class SortFirstPlan : public Plan {
 public:
  // Tiles are cut for each frame's own size (interactive frames are smaller).
  SortFirstPlan(bool balance, int tiles_per_renderer);
  void reassign(const Workers&) override {}
  void fill(proto::FrameParams& p, const Workers& w) override;
  void stats(const proto::StageStats& s, const Workers& w) override;

 private:
  struct TileReports {
    std::set<uint32_t> reported;  // renderers: a repeated report is not counted (or added) twice
    CostGrid grid{1, 1};
    std::vector<proto::TileAssignment> tiles;
  };
  bool balance_;
  int tiles_per_renderer_;
  CostGrid cost_{1, 1};
  std::map<uint64_t, TileReports> frames_;  // frames whose costs are still coming in
};

}  // namespace tessera::master
