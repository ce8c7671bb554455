// Backend selection by name (see backend.h).
#include "renderer/volume/backend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/cpu.h"
#include "common/scene.h"  // kMinStep
#include "renderer/volume/gl_volume.h"
#include "renderer/volume/raycaster.h"

namespace tessera::renderer {

RenderStats& RenderStats::operator+=(const RenderStats& o) {
  samples += o.samples;
  samples_skipped += o.samples_skipped;
  samples_terminated += o.samples_terminated;
  ms += o.ms;
  return *this;
}

Brick wholeVolume(const Volume& v) { return Brick{{0, 0, 0}, v.dims}; }

ImageF takeRecycled(int width, int height, ImageF&& recycled) {
  if (recycled.width == width && recycled.height == height && recycled.px.size() == (size_t)width * height * 4)
    return std::move(recycled);
  return ImageF(width, height, std::move(recycled.px));
}

void checkRenderArguments(const char* who, const Volume& v, int width, int height, const Brick& brick,
                          const Quality& q) {
  const std::string name(who);
  if (width <= 0 || height <= 0)
    throw std::invalid_argument(name + ": image size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  for (int a = 0; a < 3; ++a)
    if (brick.lo[a] < 0 || brick.hi[a] > v.dims[a] || brick.lo[a] >= brick.hi[a])
      throw std::invalid_argument(name + ": brick outside the volume or empty on axis " + std::to_string(a));
  if (!(q.step > 0) || !std::isfinite(q.step))
    throw std::invalid_argument(name + ": quality.step must be positive and finite");
}

Quality samplingQuality(const Quality& q, const Volume& v) {
  const Vec3 h = v.halfExtent();
  Quality sampled = q;
  // Half extents: half the sides. Never below the scene's least step (2^20 samples a ray).
  sampled.step = std::min(q.step, std::max(kMinStep, std::min({h.x, h.y, h.z})));
  return sampled;
}

BackendKind parseBackend(const std::string& name) {
  if (name == "cpu") return BackendKind::Cpu;
  if (name == "osmesa") return BackendKind::Osmesa;
  throw std::invalid_argument("volume backend '" + name + "' unknown (cpu | osmesa)");
}

const char* backendName(BackendKind kind) { return kind == BackendKind::Cpu ? "cpu" : "osmesa"; }

std::string backendProblem(BackendKind kind, const Shading& shading, Blend blend) {
  if (kind != BackendKind::Osmesa) return "";
  if (shading.on) return "the osmesa volume backend does not shade; use backend cpu or leave out `shading`";
  if (blend != Blend::Composite)
    return std::string("the osmesa volume backend composites only; use backend cpu for `blend: ") + blendName(blend) + "`";
  return "";
}

std::unique_ptr<VolumeBackend> makeVolumeBackend(BackendKind kind, std::shared_ptr<const Volume> volume,
                                                 TransferFunction tf, const Shading& shading,
                                                 const Vec3& light, Blend blend, const Crop& crop) {
  if (std::string why = backendProblem(kind, shading, blend); !why.empty()) throw std::invalid_argument(why);
  if (kind == BackendKind::Osmesa)
    return croppedBackend(std::make_unique<GlVolumeRenderer>(volume, std::move(tf)), volume, crop);
  // A bad TESSERA_SIMD or TESSERA_GATHER fails here, on the caller's thread, not in a ray-casting thread.
  cpuIsa();
  cpuGathers();
  return croppedBackend(std::make_unique<Raycaster>(volume, std::move(tf), shading, light, blend), volume, crop);
}

}  // namespace tessera::renderer
