// The volume backend interface: what a renderer needs to render one brick of a volume.
// Two implementations share the sample grid and conventions, so either can serve the farm
// and the farm still matches tessera-render: `cpu` (Raycaster, SIMD ray casting) and
// `osmesa` (GlVolumeRenderer, GLSL on llvmpipe). Implementations document their threading.
#pragma once
#include <memory>
#include <string>

#include "common/bricks.h"
#include "common/camera.h"
#include "common/image.h"
#include "common/scene.h"
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

class VolumeBackend {
 public:
  virtual ~VolumeBackend() = default;
  // Renders `brick` as seen by `cam` into a width x height premultiplied image. Pixels
  // outside the brick's screen footprint stay transparent; `active` receives the bounding
  // rectangle of pixels with alpha > 0. Counting every skipped sample has a cost: without
  // `stats` a backend may leave it out. `recycled`: an image the caller no longer needs,
  // whose memory the result takes: as it is when it is transparent and width x height (the
  // caller cleared what it had drawn, ImageF::clear), cleared when of another size.
  virtual ImageF render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                        RenderStats* stats = nullptr, Rect* active = nullptr, ImageF recycled = {}) const = 0;
};

// The image a backend renders into: `recycled` as it is when it has the size, else cleared
// in its memory (see VolumeBackend::render).
ImageF takeRecycled(int width, int height, ImageF&& recycled);

// The arguments every backend refuses the same way: a non-positive image size, a brick
// outside the volume or empty, a step that is not positive and finite. Throws
// std::invalid_argument starting with `who`.
void checkRenderArguments(const char* who, const Volume& v, int width, int height, const Brick& brick,
                          const Quality& q);

// The quality a backend samples with: `q`, its step at most half the whole volume's thinnest
// side, so that a volume of a slice or a few is sampled twice across (at the named steps a
// 1024 x 1024 x 1 slice is a quarter of a step thick and most rays would miss it).
Quality samplingQuality(const Quality& q, const Volume& v);

enum class BackendKind { Cpu, Osmesa };
// "cpu" | "osmesa"; throws std::invalid_argument naming the value otherwise.
BackendKind parseBackend(const std::string& name);
const char* backendName(BackendKind kind);
// Shading (with `light`, zero: a headlight) and `blend: maximum` or `minimum` (value pixels, see
// common/max_intensity.h) are the cpu backend's; osmesa refuses them by name: this says why
// ("" when the backend renders them), so that a renderer refuses at start, not per frame.
std::string backendProblem(BackendKind kind, const Shading& shading, Blend blend);
// Throws std::invalid_argument with backendProblem's reason. `crop`: see croppedBackend.
std::unique_ptr<VolumeBackend> makeVolumeBackend(BackendKind kind, std::shared_ptr<const Volume> volume,
                                                 TransferFunction tf, const Shading& shading = {},
                                                 const Vec3& light = {0, 0, 0}, Blend blend = Blend::Composite,
                                                 const Crop& crop = {});
// `inner`, each brick it renders cut to the scene's crop (common/scene.h) of `v`'s whole
// volume; a brick wholly outside renders transparent. `inner` itself for a whole crop.
std::unique_ptr<VolumeBackend> croppedBackend(std::unique_ptr<VolumeBackend> inner, std::shared_ptr<const Volume> v,
                                              const Crop& crop);

}  // namespace tessera::renderer
