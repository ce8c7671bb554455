// tessera-geometry-bench: the sort-first geometry mode (issue 4). (a) one process: triangles
// per second at 1024x1024, no AA and MSAA 4; (b) bounding-box culling against broadcasting
// every chunk to every tile (2x2 tiles, identical bytes required); (c) the farm through
// tessera-up on a corner-crowded scene, static against balanced tiling; (d) anti-aliasing
// run time against error (CSV + gnuplot PNG). Prints markdown tables. Not a timed test.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/bench/aa_sweep.h"
#include "common/io/image_io.h"
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

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

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
        auto t0 = std::chrono::steady_clock::now();
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
        auto t0 = std::chrono::steady_clock::now();
        cst = {};
        a = renderTiles(r, s.camera, s.width, s.height, tiles, g.chunks, opt, &cst);
        culled_ms.push_back(msSince(t0));
        t0 = std::chrono::steady_clock::now();
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
              auto t0 = std::chrono::steady_clock::now();
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

// ---- (c) the farm ---------------------------------------------------------------------------
struct FarmRow {
  std::string lp, tiling;
  int renderers = 0, frames = 0;
  double fps = 0, render_ms = 0, overlap = 0, imbalance = 0, triangles = 0, composite_ms = 0, display_ms = 0;
  bool image_ok = false;
  std::vector<double> fps_all;  // every round's fps, sorted
};

FarmRow summarizeFarm(const fs::path& metrics, size_t warm) {
  std::vector<nlohmann::json> rows;
  std::ifstream in(metrics);
  for (std::string line; std::getline(in, line);) rows.push_back(nlohmann::json::parse(line));
  std::sort(rows.begin(), rows.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
    return a["frame"].get<int>() < b["frame"].get<int>();
  });
  FarmRow f;
  f.frames = (int)rows.size();
  if (rows.size() < warm + 2) return f;
  const double n = (double)(rows.size() - warm);
  for (size_t i = warm; i < rows.size(); ++i) {
    f.render_ms += rows[i]["render_ms_max"].get<double>() / n;
    f.overlap += rows[i]["overlap_factor"].get<double>() / n;
    f.imbalance += rows[i]["render_imbalance_time"].get<double>() / n;
    f.triangles += rows[i]["triangles"].get<double>() / n;
    f.composite_ms += rows[i]["composite_ms_max"].get<double>() / n;
    f.display_ms += rows[i]["display_ms"].get<double>() / n;
  }
  f.fps = (double)(rows.size() - 1 - warm) * 1000.0 /
          (rows.back()["done_ms"].get<double>() - rows[warm]["done_ms"].get<double>());
  return f;
}

// Returns false if a run failed or a farm image differs from the one-process render.
bool farm(const Options& o) {
  const fs::path self = fs::canonical("/proc/self/exe").parent_path();
  const fs::path compose = fs::path(TESSERA_SOURCE_DIR) / "compose.yaml";
  const fs::path root = fs::absolute(o.out) / "farm";
  fs::create_directories(root);
  const fs::path scene_file = root / "corner.yaml";
  std::ofstream(scene_file) << sceneText(scenePath("corner.yaml"), o.size, o.image);
  const Scene s = loadScene(scene_file.string());

  // The one-process image every farm frame must equal (same camera every frame: no orbit),
  // through the same PNG round trip as the display's frames.
  Image8 expected;
  size_t triangles = 0;
  {
    const SceneGeometry g = loadSceneGeometry(s);
    GlRenderer r;
    r.setMesh(g.mesh);
    triangles = g.mesh.triangleCount();
    writePng((root / "one-process.png").string(),
             r.render(s.camera, s.width, s.height, {0, 0, s.width, s.height}, g.chunks, sceneRenderOptions(s)));
    expected = readPng((root / "one-process.png").string());
  }
  const size_t warm = std::min<size_t>(4, (size_t)o.frames / 4);  // start-up; balanced needs a frame of costs
  std::vector<FarmRow> rows;
  bool ok = true;
  std::vector<std::vector<FarmRow>> runs;           // per configuration, one row per round
  for (int round = 0; round < o.rounds; ++round) {  // rounds interleave configurations: load drifts
    size_t config = 0;
    for (const std::string& lp : o.lp_threads) {
      if (lp == "default")
        unsetenv("LP_NUM_THREADS");
      else
        setenv("LP_NUM_THREADS", lp.c_str(), 1);
      for (int n : o.renderers)
        for (const char* tiling : {"static", "balanced"}) {
          if (runs.size() <= config) runs.emplace_back();
          const fs::path dir = root / fmt::format("lp{}-r{}-{}-round{}", lp, n, tiling, round);
          fs::remove_all(dir);
          fs::create_directories(dir);
          const std::string cmd = fmt::format(
              "{}/tessera-up {} --env TESSERA_SCENE={} --env TESSERA_FRAMES={} --env TESSERA_RENDERERS={} "
              "--env TESSERA_COMPOSITORS=1 --env TESSERA_TILING={} --env TESSERA_OUT={} "
              "--env TESSERA_ENDPOINTS=ipc://{}/sockets --env TESSERA_WINDOW=off --env TESSERA_LOG=warn > {}/farm.log "
              "2>&1",
              self.string(), compose.string(), scene_file.string(), o.frames, n, tiling, dir.string(), dir.string(),
              dir.string());
          std::cerr << fmt::format("farm round {}: LP_NUM_THREADS={} renderers={} tiling={} ({} frames)...\n", round,
                                   lp, n, tiling, o.frames);
          ++config;
          if (std::system(cmd.c_str()) != 0) {
            std::cerr << "farm failed; see " << (dir / "farm.log").string() << "\n";
            ok = false;
            continue;
          }
          FarmRow f = summarizeFarm(dir / "metrics.jsonl", warm);
          f.lp = lp;
          f.tiling = tiling;
          f.renderers = n;
          const fs::path last = dir / fmt::format("frame_{:06d}.png", o.frames - 1);
          f.image_ok = fs::exists(last) && readPng(last.string()).px == expected.px;
          ok = ok && f.image_ok;
          runs[config - 1].push_back(f);
        }
    }
  }
  // Per configuration, the round with the median fps (all its columns from that one run).
  for (auto& v : runs) {
    if (v.empty()) continue;
    std::sort(v.begin(), v.end(), [](const FarmRow& a, const FarmRow& b) { return a.fps < b.fps; });
    FarmRow m = v[v.size() / 2];
    for (const FarmRow& f : v) m.image_ok = m.image_ok && f.image_ok;
    m.fps_all.clear();
    for (const FarmRow& f : v) m.fps_all.push_back(f.fps);
    rows.push_back(m);
  }
  std::cout
      << fmt::format(
             "\n### Farm (tessera-up, compose.yaml), {} {}x{}, {} triangles, {} frames ({} warm-up "
             "frames left out), 1 compositor; median of {} interleaved rounds by fps\n\n",
             o.image > 0 || o.size > 0 ? "corner.yaml (resized)" : "corner.yaml", s.width, s.height, triangles,
             o.frames, warm, o.rounds)
      << "| LP_NUM_THREADS | renderers | tiling | fps (done_ms) | fps of all rounds | render_ms_max mean | overlap "
         "factor | "
         "render imbalance (max/mean) | triangles drawn | composite ms | display ms | last frame == one process |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const FarmRow& f : rows)
    std::cout << fmt::format(
        "| {} | {} | {} | {:.2f} | {:.2f} | {:.1f} | {:.2f} | {:.2f} | {:.0f} | {:.1f} | {:.1f} | {} |\n", f.lp,
        f.renderers, f.tiling, f.fps, fmt::join(f.fps_all, ", "), f.render_ms, f.overlap, f.imbalance, f.triangles,
        f.composite_ms, f.display_ms, f.image_ok ? "yes" : "NO");
  std::cout << "\n| LP_NUM_THREADS | renderers | balanced / static fps | static / balanced render_ms_max "
               "|\n|---|---|---|---|\n";
  for (const FarmRow& st : rows)
    for (const FarmRow& b : rows)
      if (st.tiling == "static" && b.tiling == "balanced" && st.lp == b.lp && st.renderers == b.renderers &&
          st.fps > 0 && b.render_ms > 0)
        std::cout << fmt::format("| {} | {} | {:.2f}x | {:.2f}x |\n", st.lp, st.renderers, b.fps / st.fps,
                                 st.render_ms / b.render_ms);
  return ok;
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
  CLI::App app{"Tessera sort-first geometry benchmark (issue 4)"};
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
  app.add_option("--size", o.size, "override the scenes' generator size (0: as in the files)");
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
