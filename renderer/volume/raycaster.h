// CPU volume ray caster (docs/DESIGN.md conventions). Renders the whole volume or one brick
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
#include "renderer/volume/backend.h"

namespace tessera::renderer {

class Raycaster final : public VolumeBackend {
 public:
  // Builds the min-max hierarchy and classification tables once per volume/transfer function,
  // and with shading on the gradient volume (8 bytes per voxel). `light`: world direction
  // towards the light; zero: a headlight.
  // `blend`: Maximum renders value pixels (common/max_intensity.h), mapped by the caller once
  // every brick's are merged.
  Raycaster(std::shared_ptr<const Volume> volume, TransferFunction tf, const Shading& shading = {},
            const Vec3& light = {0, 0, 0}, Blend blend = Blend::Composite);
  ~Raycaster();

  // Renders `brick` as seen by `cam` into a width x height image. Pixels outside the
  // brick's screen footprint are never touched (left transparent). `active` receives the
  // bounding rectangle of pixels with alpha > 0.
  ImageF render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                RenderStats* stats = nullptr, Rect* active = nullptr, ImageF recycled = {}) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera::renderer
