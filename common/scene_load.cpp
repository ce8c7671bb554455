// Scenes from files, the built-in default scene, and a scene's volume read or generated.
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/scene.h"

namespace tessera {

Scene loadScene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  std::filesystem::path base = std::filesystem::path(path).parent_path();
  Scene s = parseScene(ss.str(), base.empty() ? "." : base.string(), path);
  s.path = path;
  return s;
}

Vec3 sceneHalfExtent(const Scene& s) {
  if (!s.has_volume || s.mesh) return {0.5, 0.5, 0.5};
  Volume shape;
  shape.dims = volumeDims(s);
  const auto* raw = std::get_if<RawVolumeSpec>(&s.volume);
  shape.spacing = raw ? raw->spacing : std::get<GeneratorSpec>(s.volume).spacing;
  return shape.halfExtent();
}

Scene defaultScene() {
  Scene s;
  s.path = "";
  s.volume = GeneratorSpec{"hollow-shell", 256, 1, {1, 1, 1}};
  // Shell values peak at 0.5 (semi-transparent orange), the core at 1.0 (bright, nearly opaque).
  s.tf = TransferFunction({{0.00, 0.0, 0.0, 0.0, 0.0},
                           {0.05, 1.0, 0.45, 0.1, 0.0},
                           {0.50, 1.0, 0.55, 0.15, 0.06},
                           {0.70, 1.0, 0.8, 0.5, 0.2},
                           {1.00, 1.0, 1.0, 0.9, 0.9}});
  s.camera = Camera{{0, 0.6, 2.2}, {0, 0, 0}, {0, 1, 0}, 30, false, 1};
  s.width = 1024;
  s.height = 1024;
  s.quality = namedQuality(QualityName::Default);
  s.orbit = Orbit{90, {0, 1, 0}};
  return s;
}

Volume loadVolume(const Scene& scene) { return loadVolume(scene, VoxelBox{{0, 0, 0}, volumeDims(scene)}); }

std::array<int, 3> volumeDims(const Scene& scene) {
  if (const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume)) return raw->dims;
  const int n = std::get<GeneratorSpec>(scene.volume).size;
  return {n, n, n};
}

Volume loadVolume(const Scene& scene, const VoxelBox& box, int step, std::vector<float> storage) {
  return VolumeReader(scene, step).read(box, std::move(storage));
}

// Errors name the scene and the volume key, as the parser's do.
template <class F>
auto VolumeReader::named(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(name_ + ": volume: " + e.what());
  }
}

VolumeReader::VolumeReader(const Scene& scene, int step) : name_(scene.path.empty() ? "<default scene>" : scene.path) {
  named([&] {
    auto spec = stepVolume(scene, step);
    if (auto* raw = std::get_if<RawVolumeSpec>(&spec)) raw_.emplace(std::move(*raw));
    else generated_ = std::get<GeneratorSpec>(spec);
  });
}

Volume VolumeReader::read(const VoxelBox& box, std::vector<float> storage) {
  return named([&] { return raw_ ? raw_->read(box, std::move(storage)) : generateVolume(generated_, box); });
}

}  // namespace tessera
