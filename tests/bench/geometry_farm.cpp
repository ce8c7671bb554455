#include "tests/bench/geometry_farm.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/io/image_io.h"
#include "common/scene.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh_scene.h"

namespace tessera::bench {

namespace {

namespace fs = std::filesystem;
using namespace tessera::renderer;

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

// Runs every configuration in rounds and compares each run's last frame with `expected`.
class Farm {
 public:
  Farm(const FarmConfig& c, const fs::path& root, const fs::path& scene_file, const Image8& expected)
      : c_(c), root_(root), scene_file_(scene_file), expected_(expected) {}
  size_t warm() const { return warm_; }
  bool ok() const { return ok_; }
  // Per configuration, the round with the median fps (all its columns from that one run).
  std::vector<FarmRow> run();

 private:
  void runOne(const std::string& lp, int n, const char* tiling, int round, std::vector<FarmRow>& runs);

  const FarmConfig& c_;
  const fs::path root_, scene_file_;
  const Image8& expected_;
  const fs::path self_ = fs::canonical("/proc/self/exe").parent_path();
  const fs::path compose_ = fs::path(TESSERA_SOURCE_DIR) / "compose.yaml";
  const size_t warm_ = std::min<size_t>(4, (size_t)c_.frames / 4);  // start-up; balanced needs a frame of costs
  bool ok_ = true;
};

std::vector<FarmRow> Farm::run() {
  std::vector<std::vector<FarmRow>> runs;           // per configuration, one row per round
  for (int round = 0; round < c_.rounds; ++round) {  // rounds interleave configurations: load drifts
    size_t config = 0;
    for (const std::string& lp : c_.lp_threads) {
      if (lp == "default")
        unsetenv("LP_NUM_THREADS");
      else
        setenv("LP_NUM_THREADS", lp.c_str(), 1);
      for (int n : c_.renderers)
        for (const char* tiling : {"static", "balanced"}) {
          if (runs.size() <= config) runs.emplace_back();
          runOne(lp, n, tiling, round, runs[config++]);
        }
    }
  }
  std::vector<FarmRow> rows;
  for (auto& v : runs) {
    if (v.empty()) continue;
    std::sort(v.begin(), v.end(), [](const FarmRow& a, const FarmRow& b) { return a.fps < b.fps; });
    FarmRow m = v[v.size() / 2];
    for (const FarmRow& f : v) m.image_ok = m.image_ok && f.image_ok;
    m.fps_all.clear();
    for (const FarmRow& f : v) m.fps_all.push_back(f.fps);
    rows.push_back(m);
  }
  return rows;
}

void Farm::runOne(const std::string& lp, int n, const char* tiling, int round, std::vector<FarmRow>& runs) {
  const fs::path dir = root_ / fmt::format("lp{}-r{}-{}-round{}", lp, n, tiling, round);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string cmd = fmt::format(
      "{}/tessera-up {} --env TESSERA_SCENE={} --env TESSERA_FRAMES={} --env TESSERA_RENDERERS={} "
      "--env TESSERA_COMPOSITORS=1 --env TESSERA_TILING={} --env TESSERA_OUT={} "
      "--env TESSERA_ENDPOINTS=ipc://{}/sockets --env TESSERA_WINDOW=off --env TESSERA_LOG=warn > {}/farm.log "
      "2>&1",
      self_.string(), compose_.string(), scene_file_.string(), c_.frames, n, tiling, dir.string(), dir.string(),
      dir.string());
  std::cerr << fmt::format("farm round {}: LP_NUM_THREADS={} renderers={} tiling={} ({} frames)...\n", round, lp, n,
                           tiling, c_.frames);
  if (std::system(cmd.c_str()) != 0) {
    std::cerr << "farm failed; see " << (dir / "farm.log").string() << "\n";
    ok_ = false;
    return;
  }
  FarmRow f = summarizeFarm(dir / "metrics.jsonl", warm_);
  f.lp = lp;
  f.tiling = tiling;
  f.renderers = n;
  const fs::path last = dir / fmt::format("frame_{:06d}.png", c_.frames - 1);
  f.image_ok = fs::exists(last) && readPng(last.string()).px == expected_.px;
  ok_ = ok_ && f.image_ok;
  runs.push_back(f);
}

// The one-process image every farm frame must equal (same camera every frame: no orbit),
// through the same PNG round trip as the display's frames.
Image8 oneProcessImage(const Scene& s, const fs::path& root, size_t& triangles) {
  const SceneGeometry g = loadSceneGeometry(s);
  GlRenderer r;
  r.setMesh(g.mesh);
  triangles = g.mesh.triangleCount();
  writePng((root / "one-process.png").string(),
           r.render(s.camera, s.width, s.height, {0, 0, s.width, s.height}, g.chunks, sceneRenderOptions(s)));
  return readPng((root / "one-process.png").string());
}

void printFarm(const FarmConfig& c, const Scene& s, size_t triangles, size_t warm, const std::vector<FarmRow>& rows) {
  std::cout
      << fmt::format(
             "\n### Farm (tessera-up, compose.yaml), {} {}x{}, {} triangles, {} frames ({} warm-up "
             "frames left out), 1 compositor; median of {} interleaved rounds by fps\n\n",
             c.resized ? "corner.yaml (resized)" : "corner.yaml", s.width, s.height, triangles, c.frames, warm,
             c.rounds)
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
}

}  // namespace

bool geometryFarm(const FarmConfig& c) {
  const fs::path root = fs::absolute(c.out) / "farm";
  fs::create_directories(root);
  const fs::path scene_file = root / "corner.yaml";
  std::ofstream(scene_file) << c.scene_text;
  const Scene s = loadScene(scene_file.string());
  size_t triangles = 0;
  const Image8 expected = oneProcessImage(s, root, triangles);
  Farm farm(c, root, scene_file, expected);
  const std::vector<FarmRow> rows = farm.run();
  printFarm(c, s, triangles, farm.warm(), rows);
  return farm.ok();
}

}  // namespace tessera::bench
