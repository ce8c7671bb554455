// tessera-geometry-bench: the sort-first geometry mode. (a) one process: triangles
// per second at 1024x1024, no AA and MSAA 4; (b) bounding-box culling against broadcasting
// every chunk to every tile (2x2 tiles, identical bytes required); (c) the farm through
// tessera-up on a corner-crowded scene, static against balanced tiling; (d) anti-aliasing
// run time against error (CSV + gnuplot PNG). Prints markdown tables. Not a timed test.
// Part (c) lives in geometry_farm.cpp, part (d)'s sweep in aa_sweep.cpp.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/bench/aa_sweep.h"
#include "tests/bench/geometry_farm.h"
#include "common/clock.h"
#include "common/scene.h"
#include "master/tiling.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh_scene.h"

namespace fs = std::filesystem;
using namespace tessera;
using namespace tessera::renderer;

namespace {

struct Options {
  bool smoke = false;
  std::string out = "bench-out/geometry", aa_out;
  int repeat = 5, frames = 24, rounds = 3, big_size = 256, size = 0, image = 0;
  std::vector<int> renderers{1, 2, 4};
  std::vector<std::string> lp_threads{"default"};
  std::vector<std::string> parts{"throughput", "culling", "model", "farm", "aa"};
  bool has(const std::string& p) const { return std::find(parts.begin(), parts.end(), p) != parts.end(); }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Scene text with the generator size and image size overridden (smoke runs, the 1M variant).
std::string sceneText(const std::string& path, int size, int image) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string t = ss.str();
  if (size > 0) t = std::regex_replace(t, std::regex(R"(size: *\d+)"), "size: " + std::to_string(size));
  if (image > 0)
    t = std::regex_replace(t, std::regex(R"(image: *\[[^\]]*\])"), fmt::format("image: [{0}, {0}]", image));
  return t;
}

Scene scene(const std::string& path, int size, int image) {
  Scene s = parseScene(sceneText(path, size, image), fs::path(path).parent_path().string(), path);
  if (image > 0 && (s.width != image || s.height != image)) throw std::runtime_error(path + ": image override failed");
  return s;
}

std::string scenePath(const char* name) { return (fs::path(TESSERA_SOURCE_DIR) / "scenes" / name).string(); }

// ---- (a) triangles per second -------------------------------------------------------------
void throughput(const Options& o) {
  struct Case {
    std::string label, file;
    int size;
  };
  const std::vector<Case> cases = {
      {"isosurface.yaml", "isosurface.yaml", o.size},
      {fmt::format("isosurface.yaml, size {}", o.big_size), "isosurface.yaml", o.big_size}};
  std::cout << "\n### One process: triangles per second\n\n"
            << "| scene | image | triangles | chunks | AA | ms best | ms median | M triangles/s (best) |\n"
            << "|---|---|---|---|---|---|---|---|\n";
  for (const Case& c : cases) {
    const Scene s = scene(scenePath(c.file.c_str()), c.size, o.image);
    const SceneGeometry g = loadSceneGeometry(s);
    GlRenderer r;
    r.setMesh(g.mesh);
    for (int samples : {1, 4}) {
      GlRenderOptions opt = sceneRenderOptions(s);
      opt.samples = samples;
      opt.supersample = 1;
      const Rect all{0, 0, s.width, s.height};
      (void)r.render(s.camera, s.width, s.height, all, g.chunks, opt);  // warm-up: shader JIT
      std::vector<double> ms;
      for (int i = 0; i < o.repeat; ++i) {
        auto t0 = Clock::now();
        (void)r.render(s.camera, s.width, s.height, all, g.chunks, opt);
        ms.push_back(msSince(t0));
      }
      const double best = *std::min_element(ms.begin(), ms.end());
      std::cout << fmt::format("| {} | {}x{} | {} | {} | {} | {:.1f} | {:.1f} | {:.2f} |\n", c.label, s.width, s.height,
                               g.mesh.triangleCount(), g.chunks.size(), samples == 1 ? "none" : "MSAA 4", best,
                               median(ms), g.mesh.triangleCount() / (best * 1e3));
    }
  }
}

// ---- (b) culling against broadcast --------------------------------------------------------
// Returns false if the culled and broadcast images differ.
bool culling(const Options& o) {
  std::cout
      << "\n### Bounding-box culling vs broadcast, 2x2 tiles (all 4 tiles rendered in turn)\n\n"
      << "| scene | chunk triangles | chunks | overlap factor | triangles drawn culled / broadcast | "
      << "culled ms | broadcast ms | broadcast / culled | identical bytes |\n|---|---|---|---|---|---|---|---|---|\n";
  bool ok = true;
  const std::vector<uint32_t> chunk_sizes =
      o.smoke ? std::vector<uint32_t>{256} : std::vector<uint32_t>{1024, 4096, 16384};
  for (const char* file : {"isosurface.yaml", "corner.yaml"}) {
    const Scene s = scene(scenePath(file), o.size, o.image);
    const std::vector<Rect> tiles = gridTiles(s.width, s.height, 2, 2);
    const GlRenderOptions opt = sceneRenderOptions(s);
    for (uint32_t cs : chunk_sizes) {
      const SceneGeometry g = loadSceneGeometry(s, cs);
      GlRenderer r;
      r.setMesh(g.mesh);
      auto broadcast = [&](GlRenderStats* st) {
        Image8 out(s.width, s.height);
        for (const Rect& t : tiles) {
          GlRenderStats ts;
          const Image8 part = r.render(s.camera, s.width, s.height, t, g.chunks, opt, &ts);
          for (int y = 0; y < t.h; ++y) std::copy_n(part.at(0, y), 4 * (size_t)t.w, out.at(t.x, t.y + y));
          st->triangles += ts.triangles;
          st->chunks += ts.chunks;
        }
        return out;
      };
      (void)renderTiles(r, s.camera, s.width, s.height, tiles, g.chunks, opt);  // warm-up
      std::vector<double> culled_ms, broad_ms;
      GlRenderStats cst, bst;
      Image8 a, b;
      for (int i = 0; i < o.repeat; ++i) {  // interleaved, so load changes hit both alike
        auto t0 = Clock::now();
        cst = {};
        a = renderTiles(r, s.camera, s.width, s.height, tiles, g.chunks, opt, &cst);
        culled_ms.push_back(msSince(t0));
        t0 = Clock::now();
        bst = {};
        b = broadcast(&bst);
        broad_ms.push_back(msSince(t0));
      }
      const bool same = a.px == b.px;
      ok = ok && same;
      const double cm = *std::min_element(culled_ms.begin(), culled_ms.end());
      const double bm = *std::min_element(broad_ms.begin(), broad_ms.end());
      std::cout << fmt::format("| {} | {} | {} | {:.3f} | {} / {} | {:.1f} | {:.1f} | {:.2f}x | {} |\n", file, cs,
                               g.chunks.size(), (double)cst.chunks / g.chunks.size(), cst.triangles, bst.triangles, cm,
                               bm, bm / cm, same ? "yes" : "NO");
    }
  }
  return ok;
}

// ---- (c1) tiling model: renderers on dedicated machines -------------------------------------
// The farm's tilings rendered tile by tile in this process: a renderer's time is the sum of its
// tiles' times and the frame waits for the slowest renderer, as if each renderer had its own
// machine. Balanced tiles are re-cut from the previous frame's measured per-tile times with the
// master's own k-d split (master/tiling.h), exactly as the master does.
void tilingModel(const Options& o) {
  std::cout << "\n### Tiling model (one process; renderer time = sum of its tiles, frame = slowest renderer)\n\n"
            << "| scene | chunk triangles | renderers | tiling | frame ms (slowest renderer) | sum of renderers ms | "
               "imbalance (max/mean) | overlap factor | static / balanced |\n|---|---|---|---|---|---|---|---|---|\n";
  const Scene s = scene(scenePath("corner.yaml"), o.size, o.image);
  const GlRenderOptions opt = sceneRenderOptions(s);
  const std::vector<uint32_t> chunk_sizes = o.smoke ? std::vector<uint32_t>{256} : std::vector<uint32_t>{4096, 1024};
  for (uint32_t cs : chunk_sizes) {
    const SceneGeometry g = loadSceneGeometry(s, cs);
    GlRenderer r;
    r.setMesh(g.mesh);
    const ViewProjection vp = r.viewProjection(s.camera, s.width, s.height);
    (void)r.render(s.camera, s.width, s.height, {0, 0, s.width, s.height}, g.chunks, opt);  // warm-up
    for (int n : o.renderers) {
      double static_ms = 0;
      for (const char* tiling : {"static", "balanced"}) {
        master::CostGrid cost(s.width, s.height);
        const int iters = 3;  // same for both: balanced lets its cost model settle; the last is reported
        std::vector<double> per_renderer;
        double drawn = 0;
        for (int it = 0; it < iters; ++it) {
          const std::vector<Rect> tiles = std::string(tiling) == "static"
                                              ? master::equalTiles(s.width, s.height, n)
                                              : master::balancedTiles(s.width, s.height, n, cost);
          master::CostGrid next(s.width, s.height);
          per_renderer.assign(n, 0);
          drawn = 0;
          for (size_t i = 0; i < tiles.size(); ++i) {
            double best = 1e300;
            std::vector<Chunk> draw;
            for (int c : chunksInTile(g.chunks, vp, tiles[i])) draw.push_back(g.chunks[c]);
            for (int k = 0; k < o.repeat; ++k) {  // best of repeats: the machine is shared
              auto t0 = Clock::now();
              (void)r.render(s.camera, s.width, s.height, tiles[i], draw, opt);
              best = std::min(best, msSince(t0));
            }
            next.add(tiles[i], best);
            per_renderer[i % n] += best;
            drawn += (double)draw.size();
          }
          cost = next;
        }
        const double mx = *std::max_element(per_renderer.begin(), per_renderer.end());
        double sum = 0;
        for (double v : per_renderer) sum += v;
        if (std::string(tiling) == "static") static_ms = mx;
        std::cout << fmt::format("| corner.yaml | {} | {} | {} | {:.1f} | {:.1f} | {:.2f} | {:.2f} | {} |\n", cs, n,
                                 tiling, mx, sum, mx / (sum / n), drawn / g.chunks.size(),
                                 std::string(tiling) == "balanced" ? fmt::format("{:.2f}x", static_ms / mx) : "");
      }
    }
  }
}

// ---- (c) the farm (geometry_farm.cpp) -------------------------------------------------------
bool farm(const Options& o) {
  bench::FarmConfig c;
  c.out = o.out;
  c.scene_text = sceneText(scenePath("corner.yaml"), o.size, o.image);
  c.resized = o.image > 0 || o.size > 0;
  c.frames = o.frames;
  c.rounds = o.rounds;
  c.renderers = o.renderers;
  c.lp_threads = o.lp_threads;
  return bench::geometryFarm(c);
}

// ---- (d) anti-aliasing ----------------------------------------------------------------------
void antialiasing(const Options& o) {
  const Scene s = scene(scenePath("isosurface.yaml"), o.size, o.image);
  const SceneGeometry g = loadSceneGeometry(s);
  GlRenderer r;
  r.setMesh(g.mesh);
  const bench::AaSweepResult res = bench::aaSweep(r, g, s.camera, s.width, s.height, sceneRenderOptions(s), o.repeat);
  const fs::path dir = o.aa_out.empty() ? fs::absolute(o.out) : fs::absolute(o.aa_out);
  fs::create_directories(dir);
  const std::string csv = (dir / "aa-sweep.csv").string(), png = (dir / "aa-sweep.png").string();
  bench::writeAaCsv(csv, res);
  const bool plotted = bench::plotAa(
      csv, png,
      fmt::format("Anti-aliasing: time vs error (isosurface.yaml, {}x{}, {} triangles; reference 16x SSAA)", s.width,
                  s.height, g.mesh.triangleCount()));
  std::cout << "\n### " << bench::aaMarkdown(res) << "\nwrote " << csv << (plotted ? " and " + png : "") << "\n";
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"Tessera sort-first geometry benchmark"};
  Options o;
  app.add_flag("--smoke", o.smoke, "tiny sizes, one repeat, 4 farm frames: proves it works (ctest)");
  app.add_option("--out", o.out, "folder for farm runs and outputs");
  app.add_option("--aa-out", o.aa_out, "folder for aa-sweep.csv and aa-sweep.png (default: --out)");
  app.add_option("--parts", o.parts, "any of throughput culling farm aa")->delimiter(',');
  app.add_option("--repeat", o.repeat, "timed repeats per measurement (best is reported)")->check(CLI::Range(1, 100));
  app.add_option("--frames", o.frames, "farm frames per configuration")->check(CLI::Range(4, 10000));
  app.add_option("--rounds", o.rounds, "farm: interleaved rounds per configuration (median reported)")
      ->check(CLI::Range(1, 20));
  app.add_option("--renderers", o.renderers, "farm renderer counts")->delimiter(',');
  app.add_option("--lp-threads", o.lp_threads, "farm: LP_NUM_THREADS per renderer (default = llvmpipe's)")
      ->delimiter(',');
  app.add_option("--big-size", o.big_size, "generator size of the large isosurface variant")->check(CLI::Range(8, 512));
  app.add_option("--volume-size", o.size, "override the scenes' generator size (0: as in the files)");
  app.add_option("--image", o.image, "override the scenes' image to NxN (0: as in the files)");
  CLI11_PARSE(app, argc, argv);
  if (o.smoke) {
    o.repeat = 1;
    o.frames = 4;
    o.rounds = 1;
    o.big_size = 40;
    if (o.size == 0) o.size = 24;
    if (o.image == 0) o.image = 96;
    o.renderers = {2};
  }
  std::cout << "## tessera-geometry-bench" << (o.smoke ? " (smoke)" : "") << "\n";
  if (std::ifstream la("/proc/loadavg"); la) {
    std::string l1, l5, l15;
    la >> l1 >> l5 >> l15;
    std::cout << "\nload average at start: " << l1 << " " << l5 << " " << l15 << "\n";
  }
  bool ok = true;
  if (o.has("throughput")) throughput(o);
  if (o.has("culling")) ok = culling(o) && ok;
  if (o.has("model")) tilingModel(o);
  if (o.has("farm")) ok = farm(o) && ok;
  if (o.has("aa")) antialiasing(o);
  if (!ok) std::cerr << "tessera-geometry-bench: a check failed (images differ or a farm run failed)\n";
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::cerr << "tessera-geometry-bench: " << e.what() << "\n";
  return 1;
}
