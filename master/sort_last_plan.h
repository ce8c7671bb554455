// Sort-last work: the volume split into one brick per renderer (sticky: see reassign) (by the blocks the transfer
// function may show, from a streamed summary: no voxel is held here), a back-to-front order per camera, and one screen band per compositor,
// balanced by the renderers' active pixels of the latest reported frame.
#pragma once
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "common/bricks.h"
#include "common/transfer_function.h"
#include "common/volume_summary.h"
#include "master/plan.h"

namespace tessera::master {

class SortLastPlan : public Plan {
 public:
  // Compositor bands are cut for each frame's own size (interactive frames are smaller).
  // binary_swap: frames carry a swap plan whenever the renderers allow one (SortLastWork::swap).
  // `crop`: the scene's; bricks are balanced by the visible blocks inside it.
  SortLastPlan(VolumeSummary volume, const TransferFunction& tf, bool balance, bool binary_swap = false,
               const Crop& crop = {});
  void reassign(const Workers& w) override;
  void fill(proto::FrameParams& p, const Workers& w) override;
  void stats(const proto::StageStats& s, const Workers& w) override;
  bool needsCompositors(const Workers& w) const override;

 private:
  void addSwapPlan(proto::SortLastWork& work, const Workers& w) const;
  std::optional<uint32_t> nearestAliveOwner(int brick, const std::function<bool(uint32_t)>& alive) const;

  VolumeSummary volume_;  // the master never holds the voxels
  TransferFunction tf_;  // the scene's, through its `window`: what shows decides the split
  bool balance_;
  bool binary_swap_;
  Crop crop_;
  BrickTree tree_;
  std::vector<uint32_t> owner_;  // renderer rank of each brick
  // Renderers' active rects of the latest reported frame, as fractions of its image (x0, y0,
  // x1, y1), so frames of another size can use them; by renderer, so a repeated report
  // replaces its first.
  std::map<uint32_t, std::array<double, 4>> last_active_;
  uint64_t latest_active_frame_ = 0;  // that frame + 1 (0: none yet)
  std::map<uint64_t, std::pair<int, int>> sizes_;  // frames filled and not reported yet: their size
};

}  // namespace tessera::master
