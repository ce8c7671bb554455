#include "renderer/tile_render.h"

#include <chrono>
#include <cstring>
#include <map>

#include "common/clock.h"
#include "common/wire/strips.h"

namespace tessera::renderer {

TileRenderer::TileRenderer(const Scene& scene)
    : geometry_(loadSceneGeometry(scene)), options_(sceneRenderOptions(scene)) {
  gl_.setMesh(geometry_.mesh);
}

std::vector<TileRenderer::Output> TileRenderer::render(const proto::FrameParams& p,
                                                       const proto::SortFirstWork& work, uint32_t rank,
                                                       proto::StageStats& st) {
  using Clock = std::chrono::steady_clock;
  // My tiles, grouped by the compositor that routes them.
  std::map<uint32_t, std::vector<Rect>> groups;
  for (const auto& t : work.tiles)
    if (t.renderer == rank) groups[t.compositor].push_back(t.tile);
  const ViewProjection vp = gl_.viewProjection(p.camera, p.width, p.height);
  st.chunks_total = geometry_.chunks.size();
  std::map<uint32_t, std::vector<double>> ms;  // per compositor, parallel to its tiles
  std::vector<Output> out;
  for (auto& [compositor, rects] : groups) {
    TilePacking packing = packTiles(rects, p.width);
    Image8 fb(packing.fb_width, packing.fb_height);
    double group_ms = 0;
    for (size_t i = 0; i < rects.size(); ++i) {
      auto t0 = Clock::now();
      std::vector<Chunk> draw;
      for (int c : chunksInTile(geometry_.chunks, vp, rects[i])) draw.push_back(geometry_.chunks[c]);
      GlRenderStats gs;
      Image8 tile = gl_.render(p.camera, p.width, p.height, rects[i], draw, options_, &gs);
      const PackedTile& pt = packing.tiles[i];
      for (int y = 0; y < tile.height; ++y)
        std::memcpy(fb.at(pt.fb_x, pt.fb_y + y), tile.at(0, y), 4 * (size_t)tile.width);
      double tile_ms = msSince(t0);
      ms[compositor].push_back(tile_ms);
      group_ms += tile_ms;
      st.chunks_drawn += draw.size();
      st.triangles += gs.triangles;
    }
    writeTileHeaders(packing, fb, 0);
    Output o;
    o.compositor = compositor;
    o.framebuffer.frame = p.frame;
    o.framebuffer.epoch = p.epoch;
    o.framebuffer.renderer = rank;
    o.framebuffer.width = fb.width;
    o.framebuffer.height = fb.height;
    o.framebuffer.pixels.resize(fb.px.size());
    std::memcpy(o.framebuffer.pixels.data(), fb.px.data(), fb.px.size());
    o.framebuffer.render_ms = group_ms;
    st.work_ms += group_ms;
    out.push_back(std::move(o));
  }
  // Per-tile costs in the master's order, so it can re-cut the screen by cost.
  std::map<uint32_t, size_t> next;
  for (const auto& t : work.tiles)
    if (t.renderer == rank) st.tile_ms.push_back(ms[t.compositor][next[t.compositor]++]);
  return out;
}

}  // namespace tessera::renderer
