// Loading a mesh scene's geometry (see mesh_scene.h).
#include "renderer/mesh/mesh_scene.h"

#include "renderer/mesh/marching_cubes.h"

namespace tessera::renderer {

SceneGeometry loadSceneGeometry(const Scene& scene, uint32_t per_chunk) {
  const std::string name = scene.path.empty() ? "<scene>" : scene.path;
  if (!scene.mesh) throw SceneError(name + ": not a mesh scene (no mesh: key)");
  SceneGeometry g;
  if (!scene.mesh->file.empty()) {
    try {
      g.mesh = loadMesh(scene.mesh->file);
    } catch (const std::runtime_error& e) {
      throw SceneError(name + ": mesh: " + e.what());
    }
    fitToUnitBox(g.mesh);
  } else {
    g.mesh = marchingCubes(loadVolume(scene), (float)scene.mesh->level);
    if (g.mesh.triangleCount() == 0)
      throw SceneError(name + ": mesh.isosurface.level: no surface at level " + std::to_string(scene.mesh->level));
  }
  g.chunks = buildChunks(g.mesh, per_chunk);
  return g;
}

GlRenderOptions sceneRenderOptions(const Scene& scene) {
  GlRenderOptions o;
  o.light = scene.light;
  if (scene.antialiasing.method == AaMethod::Msaa) o.samples = scene.antialiasing.samples;
  if (scene.antialiasing.method == AaMethod::Ssaa) o.supersample = scene.antialiasing.samples;
  return o;
}

}  // namespace tessera::renderer
