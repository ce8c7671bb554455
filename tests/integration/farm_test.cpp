// The farm's frames equal the one-process render (docs/DESIGN.md accuracy contract: sort-last,
// rgba8, max abs <= 1/255 per channel), for 1, 2 and 4 renderers and 1 and 2 compositors.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <nlohmann/json.hpp>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <future>
#include <thread>

#include "compositor/stage.h"
#include "display/stage.h"
#include "master/master.h"
#include "renderer/stage.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

struct Shape {
  int renderers, compositors;
  bool swap = false;  // binary swap between the renderers, bands straight to the display
};

class FarmMatchesOneProcess : public ::testing::TestWithParam<Shape> {};

TEST_P(FarmMatchesOneProcess, EveryFrameWithinOneLevel) {
  const auto [renderers, compositors, swap] = GetParam();
  FarmDir dir("match-" + std::to_string(renderers) + "x" + std::to_string(compositors) + (swap ? "-swap" : ""));
  const int frames = 3;
  auto scene = dir.writeScene(6);
  auto run = dir.runFarm(scene, renderers, compositors, frames, 120,
                         swap ? "--env TESSERA_COMPOSITING=binary-swap" : "--env TESSERA_COMPOSITING=direct-send");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("frame 3 of 3 (100%)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("run summary: 3 frames in "), std::string::npos) << run.output;
  if (swap) {
    const std::string said = "binary swap among " + std::to_string(renderers) + " renderers";
    EXPECT_NE(run.output.find(said), std::string::npos) << run.output;
  }
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    Image8 farm = dir.farmFrame(k);
    Image8 ref = dir.reference(scene, k);
    // 1/255: each brick's piece is quantized to rgba8 once before compositing.
    EXPECT_TRUE(dir.matches(farm, ref, 1, "frame_" + std::to_string(k))) << "frame " << k;
    EXPECT_GT(activeRegion(farm).area(), 100) << "frame " << k << " is (nearly) empty";
  }
  // One metrics line per frame, with every stage's report in it.
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  int lines = 0;
  for (std::string line; std::getline(metrics, line); ++lines) {
    auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["render_reports"].get<int>(), renderers);
    EXPECT_GT(j["render_bytes_raw"].get<uint64_t>(), 0u);
    EXPECT_LT(j["render_bytes_encoded"].get<uint64_t>(), j["render_bytes_raw"].get<uint64_t>() + 1024);
    EXPECT_EQ(j.contains("render_swap_ms_max"), swap) << line;
    EXPECT_GT(j["display_bytes_encoded"].get<uint64_t>(), 0u);
    if (swap) {  // the renderers' bands go straight to the display: no compositor takes part
      EXPECT_EQ(j["composite_reports"].get<int>(), 0) << line;
      continue;
    }
    EXPECT_EQ(j["composite_reports"].get<int>(), compositors);
    // Compositors report what they send (strips), not what they received; the display
    // receives exactly those messages. Decoding the pieces is timed on its own.
    EXPECT_EQ(j["composite_bytes_encoded"].get<uint64_t>(), j["display_bytes_encoded"].get<uint64_t>()) << line;
    EXPECT_GT(j["composite_bytes_raw"].get<uint64_t>(), 0u);
    EXPECT_GT(j["composite_decode_ms_max"].get<double>(), 0.0);
    EXPECT_GT(j["composite_active_pixels"].get<uint64_t>(), 100u);
  }
  EXPECT_EQ(lines, frames);
}

// Shading reads gradients, one voxel further than sampling: renderers hold two ghost voxels, and
// the farm still matches tessera-render within one level for a split into four bricks.
TEST(FarmShaded, FourRenderersMatchOneProcess) {
  FarmDir dir("shaded-4x2");
  const int frames = 2;
  auto scene = dir.writeScene(5);
  std::ofstream(scene, std::ios::app) << "shading: {specular: 0.4}\nlight: [-1, 1, 1]\n";
  auto run = dir.runFarm(scene, 4, 2, frames);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "shaded_" + std::to_string(k))) << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Shapes, FarmMatchesOneProcess,
                         ::testing::Values(Shape{1, 1}, Shape{2, 1}, Shape{2, 2}, Shape{4, 2}, Shape{2, 1, true},
                                           Shape{3, 1, true}, Shape{3, 0, true}, Shape{4, 2, true}, Shape{6, 2, true},
                                           Shape{8, 3, true}),
                         [](const auto& param_info) {
                           return std::to_string(param_info.param.renderers) + "r" + std::to_string(param_info.param.compositors) + "c" +
                                  (param_info.param.swap ? "Swap" : "");
                         });

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

// rgba8 pieces (the smallest on the wire) round each brick's colour and alpha before
// compositing and once more at the end: |error| < 1.5 levels, so 2/255 is the bound
// this mode can promise (the default rgba16f keeps the 1/255 contract, above).
TEST(FarmPixelFormats, Rgba8PiecesStayWithinTwoLevels) {
  FarmDir dir("rgba8");
  auto scene = dir.writeScene(4);
  auto run = dir.runFarm(scene, 4, 1, 2, 120, "--env TESSERA_FORMAT=rgba8");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < 2; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 2, "frame_" + std::to_string(k)));
}

// The same farm over TCP on loopback (what a cluster uses, minus the other hosts): the
// master, display and compositors listen on ports derived from one base.
TEST(FarmTransports, TcpLoopbackMatchesOneProcess) {
  FarmDir dir("tcp");
  auto scene = dir.writeScene(4);
  std::random_device rd;
  const int base = 20000 + (int)(rd() % 20000);  // PORT..PORT+2, PORT+10+rank: a free range is likely
  auto run = dir.runFarm(scene, 2, 2, 2, 120, "", "tcp://127.0.0.1:" + std::to_string(base));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("tcp://127.0.0.1:" + std::to_string(base + 11)), std::string::npos)
      << "compositor 1 should listen on base+11";
  // 1/255: the sort-last contract.
  for (int k = 0; k < 2; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k)));
}

TEST(FarmPixelFormats, Rgba32fPiecesKeepTheContract) {
  FarmDir dir("rgba32f");
  auto scene = dir.writeScene(4);
  auto run = dir.runFarm(scene, 4, 2, 2, 120, "--env TESSERA_FORMAT=rgba32f --env TESSERA_CODEC=lz4");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // 1/255: float pieces, one rounding at the end.
  for (int k = 0; k < 2; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k)));
}

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

// Issue 8: the farm at quality fast (every named preset is farm-exact) matches tessera-render.
TEST(FarmQuality, FastPresetMatchesOneProcessWithinOneLevel) {
  FarmDir dir("fast");
  auto scene = dir.writeScene(4);
  {
    std::ifstream in(scene);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    text.replace(text.find("quality: default"), 16, "quality: fast");
    std::ofstream(scene) << text;
  }
  auto run = dir.runFarm(scene, 3, 1, 2);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < 2; ++k) {
    Image8 farm = dir.farmFrame(k);
    EXPECT_TRUE(dir.matches(farm, dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
    EXPECT_GT(activeRegion(farm).area(), 100) << "frame " << k << " is (nearly) empty";
  }
}

// A frame that makes the ray caster throw (a step the scene parser would refuse, given here
// straight to the master) costs that frame, not the renderer: it logs frame= and keeps serving.
TEST(FarmFaults, RendererSurvivesAFrameThatThrows) {
  auto ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(256);
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("survives", ring));
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 16, 1};
  scene.width = 32;
  scene.height = 24;
  scene.orbit.frames = 1;
  scene.quality.step = 1e-9;  // > 2^24 samples per ray: castFast throws
  Endpoints ep = makeEndpoints("inproc://farm-renderer-survives");
  zmq::context_t ctx;
  std::atomic<bool> stop{false};
  master::MasterOptions mo;
  mo.scene = scene;
  mo.endpoints = ep;
  mo.renderers = 1;
  renderer::StageOptions ro{scene, ep, 1};
  FarmDir dir("survives");
  compositor::StageOptions co{ep, "", 512, 512, std::nullopt, sceneIdentity(scene)};
  display::StageOptions dopt{ep, (dir.path() / "out").string(), display::StageOptions::Window::Off, std::nullopt};
  dopt.scene = sceneIdentity(scene);
  auto master_done = std::async(std::launch::async, [&] { return master::run(mo, ctx, &stop); });
  auto renderer_done = std::async(std::launch::async, [&] { return renderer::runStage(ro, ctx, &stop); });
  auto compositor_done = std::async(std::launch::async, [&] { return compositor::runStage(co, ctx, &stop); });
  auto display_done = std::async(std::launch::async, [&] { return display::runStage(dopt, ctx, &stop); });
  bool logged = false;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!logged && std::chrono::steady_clock::now() < deadline &&
         renderer_done.wait_for(10ms) != std::future_status::ready) {
    for (const auto& line : ring->last_formatted())
      logged = logged || (line.find("frame=0 render failed") != std::string::npos &&
                          line.find("frames_failed=1") != std::string::npos);
  }
  const bool still_serving = renderer_done.wait_for(0s) != std::future_status::ready;
  stop = true;
  int renderer_rc = -1;
  try {
    renderer_rc = renderer_done.get();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the renderer died of the frame: " << e.what();
  }
  master_done.wait();
  compositor_done.wait();
  display_done.wait();
  spdlog::set_default_logger(previous);
  EXPECT_TRUE(logged) << "no 'frame=0 render failed ... frames_failed=1' log line";
  EXPECT_TRUE(still_serving);
  EXPECT_EQ(renderer_rc, 0);
}

}  // namespace
}  // namespace tessera::test
