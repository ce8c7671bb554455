// Backend selection by name (see backend.h).
#include "renderer/volume/backend.h"

#include <stdexcept>

#include "common/cpu.h"
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

BackendKind parseBackend(const std::string& name) {
  if (name == "cpu") return BackendKind::Cpu;
  if (name == "osmesa") return BackendKind::Osmesa;
  throw std::invalid_argument("volume backend '" + name + "' unknown (cpu | osmesa)");
}

const char* backendName(BackendKind kind) { return kind == BackendKind::Cpu ? "cpu" : "osmesa"; }

std::unique_ptr<VolumeBackend> makeVolumeBackend(BackendKind kind, std::shared_ptr<const Volume> volume,
                                                 TransferFunction tf) {
  if (kind == BackendKind::Osmesa) return std::make_unique<GlVolumeRenderer>(std::move(volume), std::move(tf));
  cpuIsa();  // a bad TESSERA_SIMD fails here, on the caller's thread, not in a ray-casting thread
  return std::make_unique<Raycaster>(std::move(volume), std::move(tf));
}

}  // namespace tessera::renderer
