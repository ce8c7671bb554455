// CPU volume ray caster (DESIGN.md conventions). Renders the whole volume or one brick
// (an axis-aligned voxel sub-box) into a premultiplied RGBA float image. Sample positions
// are global along each ray (t0 + k*step from the whole-volume entry), so bricks rendered
// separately and composited front-to-back reproduce the whole-volume image. With empty-space
// skipping, rays are also cut to the box of blocks the transfer function leaves non-empty;
// the fast path casts rays in pairs (see kernels.h); neither changes a bit of the image.
// A Raycaster is immutable after construction and safe to call from many threads.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/bricks.h"
#include "common/camera.h"
#include "common/image.h"
#include "common/scene.h"
#include "common/transfer_function.h"
#include "common/volume.h"

namespace tessera::renderer {

// Voxel index box [lo, hi) on each axis. Its spatial extent is the union of its cells.
using Brick = BrickBox;
Brick wholeVolume(const Volume& v);

struct RenderStats {
  uint64_t samples = 0;             // samples classified and composited
  uint64_t samples_skipped = 0;     // samples passed over by empty-space skipping
  uint64_t samples_terminated = 0;  // samples not taken because of early ray termination
  double ms = 0;
  RenderStats& operator+=(const RenderStats& o);
};

struct RenderOptions {
  Quality quality;
  int threads = 0;  // 0: hardware concurrency
};

class Raycaster {
 public:
  // Builds the min-max hierarchy and classification tables once per volume/transfer function.
  Raycaster(std::shared_ptr<const Volume> volume, TransferFunction tf);
  ~Raycaster();

  // Renders `brick` as seen by `cam` into a width x height image. Pixels outside the
  // brick's screen footprint are never touched (left transparent). `active` receives the
  // bounding rectangle of pixels with alpha > 0.
  ImageF render(const Camera& cam, int width, int height, const Brick& brick,
                const RenderOptions& opt, RenderStats* stats = nullptr, Rect* active = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera::renderer
