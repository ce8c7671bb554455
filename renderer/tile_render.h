// Sort-first rendering in a renderer stage: draws this renderer's tiles of a frame with
// OSMesa (only the chunks whose screen box touches each tile) and packs them into one
// framebuffer per router, each tile row preceded by its two-pixel strip header.
// Owns an OpenGL context: use from one thread.
#pragma once
#include <memory>
#include <vector>

#include "common/wire/protocol.h"
#include "common/scene.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh_scene.h"

namespace tessera::renderer {

class TileRenderer {
 public:
  explicit TileRenderer(const Scene& scene);  // loads the geometry, creates the GL context

  struct Output {
    uint32_t compositor = 0;
    proto::Framebuffer framebuffer;
  };
  // Fills st.tile_ms (per tile of this renderer, in work.tiles order), chunks and triangles.
  std::vector<Output> render(const proto::FrameParams& p, const proto::SortFirstWork& work, uint32_t rank,
                             proto::StageStats& st);
  size_t chunkCount() const { return geometry_.chunks.size(); }

 private:
  SceneGeometry geometry_;
  GlRenderOptions options_;
  GlRenderer gl_;
};

}  // namespace tessera::renderer
