#include "renderer/brick_images.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/net/log.h"

namespace tessera::renderer {

BrickImages::BrickImages(const Scene& scene, BackendKind backend, int cache_mb, int threads)
    : scene_(scene), cache_mb_(cache_mb), threads_(threads), steps_(scene, backend, (uint64_t)cache_mb << 20) {}

void BrickImages::hold(const proto::FrameParams& p, const proto::SortLastWork& work, uint32_t rank, proto::StageStats& st) {
  const auto whole = volumeDims(scene_);
  // Trilinear sampling near a brick face reads one voxel beyond it; its gradient, one more.
  const int ghost = scene_.shading.on ? 2 : 1;
  VoxelBox need{whole, {0, 0, 0}};
  for (const auto& b : work.bricks) {
    if (b.renderer != rank) continue;
    for (int a = 0; a < 3; ++a) {
      need.lo[a] = std::min(need.lo[a], std::max(0, b.brick.lo[a] - ghost));
      need.hi[a] = std::max(need.hi[a], std::min(whole[a], b.brick.hi[a] + ghost));
    }
  }
  if (need.lo[0] >= need.hi[0]) return;  // no brick of ours this frame
  // Same window as before: keep the window held for it (bricks within the held window
  // after a neighbour's loss are rendered from it).
  if (held_.volume) {
    bool inside = true;
    for (int a = 0; a < 3; ++a)
      inside = inside && need.lo[a] >= held_.volume->origin[a] && need.hi[a] <= held_.volume->origin[a] + held_.volume->dims[a];
    if (inside) need = VoxelBox{held_.volume->origin, {held_.volume->origin[0] + held_.volume->dims[0],
                                                       held_.volume->origin[1] + held_.volume->dims[1],
                                                       held_.volume->origin[2] + held_.volume->dims[2]}};
    else held_ = {};  // before loading the next: peak memory is one window
  }
  held_ = steps_.get(need, (int)p.step, p.window);
  const StepCacheStats cs = steps_.take();
  st.load_ms = cs.load_ms;
  if (scene_.series.steps > 1) {
    st.step = (uint32_t)held_.step;
    st.step_hits = cs.hits;
    st.step_misses = cs.misses;
    st.bytes_read = cs.bytes_read;
    st.prefetch_ms = cs.prefetch_ms;
  }
  if (!held_.volume) throw std::runtime_error("step " + std::to_string(p.step) + " could not be read and no other step is held");
  if (cs.load_ms > 0)
    spdlog::info("frame={} step={} loaded voxels [{}, {}, {}] .. [{}, {}, {}) ({:.1f} MiB) in {:.0f} ms", p.frame, p.step,
                 need.lo[0], need.lo[1], need.lo[2], need.hi[0], need.hi[1], need.hi[2],
                 (double)held_.volume->voxelCount() * sizeof(float) / (1 << 20), cs.load_ms);
}

const BrickImages::Image& BrickImages::render(const proto::FrameParams& p, const BrickBox& brick, proto::StageStats& st,
                                              const Image* in_rounds) {
  Image::Key key{p.camera, p.quality, p.width, p.height, brick, held_.step, p.window};
  for (auto& c : images_)
    if (c.key == key) return ++st.images_reused, c;  // unchanged inputs: reuse, do not render again
  ++st.images_made;
  RenderOptions ro;
  ro.quality = p.quality;
  ro.threads = threads_;
  Image c{key, {}, {}};
  Brick local = brick;  // in the held window's voxel indices
  for (int a = 0; a < 3; ++a) local.lo[a] -= held_.volume->origin[a], local.hi[a] -= held_.volume->origin[a];
  // No RenderStats: the farm needs no sample counts, and counting skipped samples costs.
  ImageF spare;  // the oldest image's memory, so that a frame does not fault in fresh pages
  if (images_.size() >= 2) {  // a renderer may own two bricks after a failure
    auto oldest = images_.begin();
    if (&*oldest == in_rounds) ++oldest;  // an end of the deque: the other entry stays in place
    oldest->image.clear(oldest->active);  // all it drew: the rest of it is transparent
    spare = std::move(oldest->image);
    images_.erase(oldest);
  }
  c.image = held_.caster->render(p.camera, p.width, p.height, local, ro, nullptr, &c.active, std::move(spare));
  images_.push_back(std::move(c));
  return images_.back();
}

void BrickImages::prefetch(const std::deque<proto::FrameParams>& queued) {
  // The steps the queued frames will show, soonest first, then the one the master expects
  // after the last. The first frame's own step is among them (it is about to be shown): the
  // prefetch thread reads steps in the order they are shown, which a gzip stream needs (a
  // later step read first would make it start again from the file's beginning).
  std::vector<int> steps;
  for (const auto& p : queued)
    for (int s : {(int)p.step, (int)p.next_step})
      if (std::find(steps.begin(), steps.end(), s) == steps.end()) steps.push_back(s);
  steps_.prefetch(steps);
}

void BrickImages::logSteps() {
  if (scene_.series.steps <= 1) return;
  const StepCacheStats s = steps_.take();
  spdlog::info("step cache: budget {} MiB, held at most {:.1f} MiB besides the shown step; {} hits, {} misses, {} bad steps",
               cache_mb_, (double)s.peak_bytes / (1 << 20), s.hits, s.misses, s.bad_steps);
}

}  // namespace tessera::renderer
