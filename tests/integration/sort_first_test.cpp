// Sort-first geometry through the real farm: renderers draw their screen tiles on OSMesa,
// pack them with strip headers, compositors route the strips by their headers alone.
// docs/DESIGN.md contract: the farm's frames are bit-identical to the one-process render at the
// same size and sample count, for any tiling.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

struct Case {
  int renderers, compositors;
  std::string tiling;
  int tiles_per_renderer;
  std::string aa;  // the scene's antialiasing
};

fs::path writeMeshScene(const FarmDir& dir, const std::string& aa, int frames) {
  fs::path p = dir.path() / "mesh.yaml";
  std::ofstream(p) << "volume:\n  generator: {name: marschner-lobb, size: 24}\n"
                   << "mesh:\n  isosurface: {of: volume, level: 0.5}\n"
                   << "camera: {eye: [1.2, 1.5, 1.9], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                   << "light: [0.4, 1.0, 0.6]\n"
                   << "antialiasing: " << aa << "\n"
                   << "image: [97, 83]\n"
                   << "orbit: {frames: " << frames << ", axis: [0, 1, 0]}\n";
  return p;
}

class SortFirstFarm : public ::testing::TestWithParam<Case> {};

TEST_P(SortFirstFarm, FramesAreBitIdenticalToOneProcess) {
  const Case c = GetParam();
  FarmDir dir("sortfirst");
  const int frames = 3;
  auto scene = writeMeshScene(dir, c.aa, 8);
  auto run = dir.runFarm(scene, c.renderers, c.compositors, frames, 120,
                         "--env TESSERA_TILING=" + c.tiling +
                             " --env TESSERA_TILES_PER_RENDERER=" + std::to_string(c.tiles_per_renderer));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << "\n" << run.output;
    Image8 farm = dir.farmFrame(k);
    Image8 ref = dir.reference(scene, k);
    EXPECT_TRUE(dir.matches(farm, ref, 0, "frame_" + std::to_string(k)));  // bit-identical
    EXPECT_GT(activeRegion(farm).area(), 500) << "frame " << k << " is (nearly) empty";
  }
  // Every frame reports how much geometry the tiles drew (overlap) and the balance.
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  int lines = 0;
  const Image8 first = dir.farmFrame(0);
  for (std::string line; std::getline(metrics, line); ++lines) {
    auto j = nlohmann::json::parse(line);
    // The tiles cover the image once: compositors route every pixel of it (pixels, not strips).
    EXPECT_EQ(j["composite_active_pixels"].get<uint64_t>(), uint64_t(first.width) * first.height) << line;
    EXPECT_EQ(j["composite_bytes_encoded"].get<uint64_t>(), j["display_bytes_encoded"].get<uint64_t>()) << line;
    EXPECT_GE(j["overlap_factor"].get<double>(), 1.0 - 1e-9) << line;
    EXPECT_GT(j["triangles"].get<double>(), 0) << line;
    EXPECT_EQ(j["strips_rejected"].get<int>(), 0);
  }
  EXPECT_EQ(lines, frames);
}

// A mesh that covers every row of every tile: each tile row is a strip of its own with its own
// header, so one compositor's stream of two tiles side by side holds two headers a row. The
// display once took more than one header a row for a malformed stream, dropped every such
// frame and blamed the compositor, and the farm never got past its first frame.
TEST(SortFirstFarmFull, AMeshCoveringEveryTileRowReachesTheDisplay) {
  FarmDir dir("sortfirst-full");
  const int frames = 2;
  fs::path scene = dir.path() / "full.yaml";
  std::ofstream(scene) << "volume:\n  generator: {name: marschner-lobb, size: 24}\n"
                       << "mesh:\n  isosurface: {of: volume, level: 0.5}\n"
                       << "camera: {eye: [0.05, 0.1, 2], target: [0, 0, 0], up: [0, 1, 0], fov: 15}\n"
                       << "light: [0.4, 1.0, 0.6]\nantialiasing: {method: none}\nimage: [97, 83]\n"
                       << "orbit: {frames: 64, axis: [0, 1, 0]}\n";
  auto run = dir.runFarm(scene, 2, 1, frames, 60, "--env TESSERA_TILING=static");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << "\n" << run.output;
    Image8 farm = dir.farmFrame(k);
    EXPECT_TRUE(dir.matches(farm, dir.reference(scene, k), 0, "full_" + std::to_string(k)));  // bit-identical
    // Every row of the frame has content, so every tile row was a strip of its own.
    int full_rows = 0;
    for (int y = 0; y < farm.height; ++y) {
      bool left = false, right = false;
      for (int x = 0; x < farm.width; ++x) (x < farm.width / 2 ? left : right) |= farm.at(x, y)[3] != 0;
      full_rows += left && right;
    }
    EXPECT_EQ(full_rows, farm.height) << "frame " << k << " does not cover both halves of every row";
  }
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  for (std::string line; std::getline(metrics, line);) {
    auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["strips_rejected"].get<int>(), 0) << line;
    EXPECT_EQ(j["display_dropped"].get<int>(), 0) << line;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Tilings, SortFirstFarm,
    ::testing::Values(Case{1, 1, "static", 1, "{method: none}"}, Case{2, 1, "balanced", 1, "{method: none}"},
                      Case{3, 2, "static", 3, "{method: msaa, samples: 4}"},
                      Case{4, 2, "balanced", 1, "{method: msaa, samples: 4}"},
                      Case{2, 2, "static", 5, "{method: ssaa, samples: 2}"}),
    [](const auto& param_info) {
      const Case& c = param_info.param;
      std::string aa = c.aa.find("msaa") != std::string::npos ? "msaa" : c.aa.find("ssaa") != std::string::npos ? "ssaa" : "noaa";
      return std::to_string(c.renderers) + "r" + std::to_string(c.compositors) + "c_" + c.tiling + "_" +
             std::to_string(c.tiles_per_renderer) + "t_" + aa;
    });

}  // namespace
}  // namespace tessera::test
