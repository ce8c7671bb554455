// The scene's `crop` for any backend: each brick is rendered cut to the crop box. Bricks that
// tile the volume, cut so, tile the crop box exactly, so a farm's bricks and one process's
// whole volume render the same samples (on the same grid along each ray), and trilinear
// neighbours and gradients at the cut are the volume's own voxels (the ghost layer).
#include <algorithm>
#include <cmath>

#include "renderer/volume/backend.h"

namespace tessera::renderer {
namespace {

class Cropped : public VolumeBackend {
 public:
  Cropped(std::unique_ptr<VolumeBackend> inner, std::shared_ptr<const Volume> v, const Crop& crop)
      : inner_(std::move(inner)), volume_(std::move(v)) {
    const VoxelBox whole = cropBox(crop, volume_->wholeDims());
    for (int a = 0; a < 3; ++a)  // in the held window's indices, as the bricks are given
      box_.lo[a] = whole.lo[a] - volume_->origin[a], box_.hi[a] = whole.hi[a] - volume_->origin[a];
    // The step, at most half the crop box's thinnest side, as a thin volume's is at most half
    // its box's (samplingQuality): a slab of one voxel is sampled across, not passed between
    // two samples. The box is the whole volume's, so every brick keeps one grid.
    const Vec3 h = volume_->halfExtent();
    double thinnest = INFINITY;
    for (int a = 0; a < 3; ++a)
      thinnest = std::min(thinnest, (whole.hi[a] - whole.lo[a]) * 2 * h[a] / volume_->wholeDims()[a]);
    max_step_ = std::max(kMinStep, thinnest / 2);
  }

  ImageF render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                RenderStats* stats, Rect* active, ImageF recycled) const override {
    checkRenderArguments("crop", *volume_, width, height, brick, opt.quality);  // refused as uncropped
    Brick cut;
    for (int a = 0; a < 3; ++a) {
      cut.lo[a] = std::max(brick.lo[a], box_.lo[a]), cut.hi[a] = std::min(brick.hi[a], box_.hi[a]);
      if (cut.lo[a] >= cut.hi[a]) {  // wholly cut away: transparent, as a brick that is empty
        if (active) *active = Rect{};
        if (stats) *stats = RenderStats{};
        return takeRecycled(width, height, std::move(recycled));
      }
    }
    RenderOptions o = opt;
    o.quality.step = std::min(o.quality.step, max_step_);
    return inner_->render(cam, width, height, cut, o, stats, active, std::move(recycled));
  }

 private:
  std::unique_ptr<VolumeBackend> inner_;
  std::shared_ptr<const Volume> volume_;
  Brick box_;
  double max_step_;
};

}  // namespace

std::unique_ptr<VolumeBackend> croppedBackend(std::unique_ptr<VolumeBackend> inner, std::shared_ptr<const Volume> v,
                                              const Crop& crop) {
  if (crop.whole()) return inner;
  return std::make_unique<Cropped>(std::move(inner), std::move(v), crop);
}

}  // namespace tessera::renderer
