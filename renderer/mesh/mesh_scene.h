// The geometry of a mesh scene (Scene::mesh): a PLY/OBJ file fitted to the unit box, or the
// marching-cubes isosurface of the scene's volume; chunked for sort-first culling.
#pragma once
#include <vector>

#include "common/scene.h"
#include "renderer/mesh/chunks.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

inline constexpr uint32_t kDefaultChunkTriangles = 4096;

struct SceneGeometry {
  Mesh mesh;                  // triangles in chunk order
  std::vector<Chunk> chunks;
};

// Throws SceneError naming the scene for a scene without mesh:, an unreadable mesh or an
// isosurface with no triangles at its level.
SceneGeometry loadSceneGeometry(const Scene& scene, uint32_t triangles_per_chunk = kDefaultChunkTriangles);

// The scene's light and antialiasing as renderer options (fft: the post filter is the caller's).
GlRenderOptions sceneRenderOptions(const Scene& scene);

}  // namespace tessera::renderer
