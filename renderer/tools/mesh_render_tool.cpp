// Geometry path of tessera-render (see mesh_render_tool.h).
#include "renderer/tools/mesh_render_tool.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "common/clock.h"
#include "common/io/image_io.h"
#include "renderer/tools/fft_filter.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh_scene.h"

namespace tessera::renderer {

namespace {


struct Frame {
  Image8 image;
  double ms = 0;  // best of repeats, including the FFT post filter
  GlRenderStats stats;
};

Frame renderFrame(GlRenderer& r, const SceneGeometry& g, const Camera& cam, int w, int h, const std::vector<Rect>& tiles,
                  const Antialiasing& aa, const GlRenderOptions& base, int repeat) {
  GlRenderOptions o = base;
  o.samples = aa.method == AaMethod::Msaa ? aa.samples : 1;
  o.supersample = aa.method == AaMethod::Ssaa ? aa.samples : 1;
  Frame f;
  f.ms = 1e300;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f.image = renderTiles(r, cam, w, h, tiles, g.chunks, o, &f.stats);
    // Whole-image post filter: per tile it would differ near the tile borders.
    if (aa.method == AaMethod::Fft) lowPassFilter(f.image, aa.sigma);
    f.ms = std::min(f.ms, msSince(t0));
  }
  return f;
}

}  // namespace

int renderMeshScene(const Scene& scene, const MeshToolOptions& opt) {
  const int w = opt.width > 0 ? opt.width : scene.width, h = opt.height > 0 ? opt.height : scene.height;
  Antialiasing aa = scene.antialiasing;
  if (!opt.aa.empty()) {
    try {
      aa.method = parseAaMethod(opt.aa);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--aa: ") + e.what());
    }
    aa.samples = aa.method == AaMethod::Msaa ? 4 : aa.method == AaMethod::Ssaa ? 2 : 1;
  }
  if (opt.aa_samples > 0) aa.samples = opt.aa_samples;

  const auto t_load = std::chrono::steady_clock::now();
  const SceneGeometry g = loadSceneGeometry(scene);
  const double load_ms = msSince(t_load);
  GlRenderer r;
  const auto t_up = std::chrono::steady_clock::now();
  r.setMesh(g.mesh);
  const double upload_ms = msSince(t_up);
  const Camera cam = scene.orbit.at(scene.camera, opt.frame);
  const std::vector<Rect> tiles = gridTiles(w, h, opt.tile_cols, opt.tile_rows);
  const GlRenderOptions base = sceneRenderOptions(scene);

  const Frame f = renderFrame(r, g, cam, w, h, tiles, aa, base, opt.repeat);
  writePng(opt.out, f.image, opt.background);
  if (!opt.pam.empty()) writePam(opt.pam, f.image);
  std::printf("wrote %s (%dx%d, %zu triangles in %zu chunks, %zu tile%s, antialiasing %s %d, frame %d)\n",
              opt.out.c_str(), w, h, g.mesh.triangleCount(), g.chunks.size(), tiles.size(),
              tiles.size() == 1 ? "" : "s", aaMethodName(aa.method), aa.samples, opt.frame);
  if (opt.stats) {
    const double overlap = (double)f.stats.chunks / std::max<size_t>(1, g.chunks.size());
    std::printf("time_ms=%.1f%s triangles_drawn=%llu mtri_per_s=%.2f overlap=%.3f load_ms=%.0f upload_ms=%.0f\n", f.ms,
                opt.repeat > 1 ? " (best of repeats)" : "", (unsigned long long)f.stats.triangles,
                g.mesh.triangleCount() / (f.ms * 1e3), overlap, load_ms, upload_ms);
  }
  if (opt.compare_reference || opt.aa_sweep) {
    const std::vector<Rect> whole{Rect{0, 0, w, h}};
    const Frame ref = renderFrame(r, g, cam, w, h, whole, Antialiasing{AaMethod::Ssaa, 4, 0}, base, 1);
    if (opt.compare_reference) {
      const ImageError e = compare(f.image, ref.image);
      std::printf("vs 16x supersampled: max_abs=%.6f rmse=%.6f psnr=%.2f dB (reference %.0f ms)\n", e.max_abs, e.rmse,
                  e.psnr, ref.ms);
    }
    if (opt.aa_sweep) {
      std::printf("method,samples,ms,rmse,psnr_db,max_abs\n");
      using enum AaMethod;
      const Antialiasing methods[] = {{None, 1, 0}, {Msaa, 2, 0}, {Msaa, 4, 0}, {Ssaa, 2, 0},
                                      {Ssaa, 3, 0}, {Fft, 1, 0.5}, {Fft, 1, 0.7}, {Fft, 1, 1.0}};
      for (const Antialiasing& m : methods) {
        const Frame mf = renderFrame(r, g, cam, w, h, whole, m, base, opt.repeat);
        const ImageError e = compare(mf.image, ref.image);
        std::printf("%s%s,%d,%.1f,%.6f,%.2f,%.4f\n", aaMethodName(m.method),
                    m.method == Fft ? ("(sigma=" + std::to_string(m.sigma).substr(0, 3) + ")").c_str() : "",
                    m.samples, mf.ms, e.rmse, e.psnr, e.max_abs);
      }
    }
  }
  return 0;
}

}  // namespace tessera::renderer
