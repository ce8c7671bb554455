// Second volume backend: GLSL ray casting on OSMesa (llvmpipe) over a 3D texture, with
// directional min-max distance maps for empty-space leaps. Same conventions, sample grid
// and render() signature as Raycaster, so a farm renderer can use either; reference quality
// is delegated to the CPU double-precision path. Owns one OSMesa context; render() is
// serialized by a mutex and may be called from any thread (the context is made current).
#pragma once
#include <memory>

#include "renderer/volume/raycaster.h"

namespace tessera::renderer {

class GlVolumeRenderer final : public VolumeBackend {
 public:
  // Creates the context, uploads the volume (R16, quantized like the CPU fast path) and
  // the min-max distance maps. Throws std::runtime_error with one line if the OSMesa
  // context cannot be created, std::invalid_argument for a bad volume/transfer function.
  GlVolumeRenderer(std::shared_ptr<const Volume> volume, TransferFunction tf);
  ~GlVolumeRenderer();
  GlVolumeRenderer(const GlVolumeRenderer&) = delete;
  GlVolumeRenderer& operator=(const GlVolumeRenderer&) = delete;

  // As Raycaster::render. opt.threads sizes the CPU ray setup only; llvmpipe's own thread
  // count comes from LP_NUM_THREADS (default: all cores).
  ImageF render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                RenderStats* stats = nullptr, Rect* active = nullptr, ImageF recycled = {}) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera::renderer
