// OSMesa (OpenGL 4.5 core, llvmpipe) triangle renderer for sort-first tiles. A tile is drawn
// with the full image's projection and viewport on a full-size framebuffer, limited by the
// scissor test, so its pixels are bit-identical to the same pixels of a full-frame render.
// One GlRenderer owns one context; use it from one thread at a time.
#pragma once
#include <GL/osmesa.h>

#include <memory>
#include <span>
#include <vector>

#include "common/camera.h"
#include "common/image.h"
#include "renderer/gl/gl_context.h"
#include "renderer/mesh/chunks.h"
#include "renderer/mesh/mesh.h"
#include "renderer/gl/projection.h"

namespace tessera::renderer {

struct GlRenderOptions {
  int samples = 1;      // MSAA samples per pixel: 1, 2 or 4 (llvmpipe renders 2 as 4)
  int supersample = 1;  // k: render k x k times the pixels and box-filter down (1..8)
  Vec3 light{0, 0, 0};  // world direction towards the light; zero: a headlight
  float ambient = 0.25f;
  bool operator==(const GlRenderOptions&) const = default;
};

struct GlRenderStats {
  double ms = 0;               // wall time of render()
  uint64_t triangles = 0;      // triangles submitted (after chunk culling)
  int chunks = 0;              // chunks submitted
};

class GlRenderer {
 public:
  // Throws std::runtime_error "OSMesa: cannot create ..." naming the context asked for.
  GlRenderer();
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  // Uploads the mesh's vertex and index buffers once; its bounds set near/far for every frame.
  // Call buildChunks before this if the mesh is to be drawn by chunks.
  void setMesh(const Mesh& mesh);
  const Box& meshBounds() const { return bounds_; }
  size_t triangleCount() const { return triangles_; }

  // The projection every tile of a width x height image of this mesh uses.
  ViewProjection viewProjection(const Camera& cam, int width, int height) const {
    return makeViewProjection(cam, width, height, bounds_);
  }

  // Renders `tile` (top-left origin, inside the width x height image) drawing only `draw`
  // (chunk ranges of the uploaded mesh, in the given order). Returns the tile's premultiplied
  // rgba8 pixels, rows top to bottom. Chunks that cannot touch the tile may be left out without
  // changing a byte (see chunksInTile). Throws std::invalid_argument for a bad tile or options.
  Image8 render(const Camera& cam, int width, int height, const Rect& tile, std::span<const Chunk> draw,
                const GlRenderOptions& opt = {}, GlRenderStats* stats = nullptr);
  // All triangles as one chunk.
  Image8 render(const Camera& cam, int width, int height, const Rect& tile, const GlRenderOptions& opt = {},
                GlRenderStats* stats = nullptr);

 private:
  void makeCurrent();
  void ensureTargets(int width, int height, int samples);
  uint64_t drawChunks(std::span<const Chunk> draw);  // consecutive chunks in one call; returns triangles
  void releaseTargets();

  gl::GlContext context_;
  unsigned program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0;
  int loc_mvp_ = -1, loc_view_ = -1, loc_light_ = -1, loc_ambient_ = -1;
  // Framebuffers: `draw` (multisampled when samples > 1) and `resolve` (single sample).
  unsigned fbo_draw_ = 0, fbo_resolve_ = 0, rb_color_ = 0, rb_depth_ = 0, rb_resolve_ = 0;
  int fb_w_ = 0, fb_h_ = 0, fb_samples_ = 0;
  Box bounds_;
  size_t triangles_ = 0;
};

// A cols x rows grid of tiles covering the image; sizes differ by at most one pixel.
std::vector<Rect> gridTiles(int width, int height, int cols, int rows);
// Renders every tile (culling chunks per tile) and assembles them into one image, as the farm
// will. `stats` sums the tiles.
Image8 renderTiles(GlRenderer& r, const Camera& cam, int width, int height, const std::vector<Rect>& tiles,
                   const std::vector<Chunk>& chunks, const GlRenderOptions& opt = {}, GlRenderStats* stats = nullptr);

}  // namespace tessera::renderer
