// The whole farm inside one process over inproc:// (the transport the stages share with
// ipc:// and tcp://): a renderer that vanishes mid-run is detected by heartbeat, its
// bricks are reassigned under a new epoch, and every frame still matches the one-process
// render.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/io/image_io.h"
#include "common/net/stage_link.h"
#include "compositor/stage.h"
#include "display/stage.h"
#include "tests/integration/farm_util.h"
#include "master/interaction.h"
#include "master/master.h"
#include "renderer/volume/raycaster.h"
#include "renderer/stage.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

TEST(InProcessFarm, LostRendererIsDetectedAndItsWorkReassigned) {
  FarmDir dir("inproc");
  const int frames = 40;
  Scene scene = smallScene(frames);
  Endpoints ep = makeEndpoints("inproc://farm-lost-renderer");
  zmq::context_t ctx;
  std::atomic<bool> stop_all{false}, stop_r1{false};

  master::MasterOptions mo;
  mo.scene = scene;
  mo.endpoints = ep;
  mo.renderers = 2;
  mo.heartbeat_timeout_s = 0.5;
  mo.metrics_path = (dir.path() / "metrics.jsonl").string();
  renderer::StageOptions ro{scene, ep, 1};
  compositor::StageOptions co{ep, "", 512, 512, std::nullopt, sceneIdentity(scene)};
  display::StageOptions dopt{ep, (dir.path() / "out").string(), display::StageOptions::Window::Off, std::nullopt};
  dopt.scene = sceneIdentity(scene);

  std::vector<std::future<int>> stages;
  stages.push_back(std::async(std::launch::async, [&] { return master::run(mo, ctx, &stop_all); }));
  stages.push_back(std::async(std::launch::async, [&] { return renderer::runStage(ro, ctx, &stop_all); }));
  auto lost = std::async(std::launch::async, [&] { return renderer::runStage(ro, ctx, &stop_r1); });
  stages.push_back(std::async(std::launch::async, [&] { return compositor::runStage(co, ctx, &stop_all); }));
  stages.push_back(std::async(std::launch::async, [&] { return display::runStage(dopt, ctx, &stop_all); }));

  // Let a few frames through, then the second renderer vanishes without a word.
  auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!fs::exists(dir.frame(3)) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
  stop_r1 = true;
  EXPECT_EQ(lost.get(), 0);

  bool finished = true;
  for (auto& f : stages) finished = finished && f.wait_for(60s) == std::future_status::ready;
  if (!finished) stop_all = true;  // do not hang the suite: stop and report
  for (auto& f : stages) EXPECT_EQ(f.get(), 0);
  ASSERT_TRUE(finished) << "the farm did not finish after losing a renderer";

  auto volume = std::make_shared<Volume>(loadVolume(scene));
  renderer::Raycaster caster(volume, scene.tf);
  renderer::RenderOptions opt;
  opt.quality = scene.quality;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing";
    Camera cam = scene.orbit.at(scene.camera, k);
    Image8 ref = toRGBA8(caster.render(cam, scene.width, scene.height, renderer::wholeVolume(*volume), opt));
    // 1/255: pieces are quantized to rgba8 once before compositing.
    EXPECT_TRUE(dir.matches(readPng(dir.frame(k).string()), ref, 1, "frame_" + std::to_string(k)));
  }
  // The metrics show the new epoch: the master noticed and reassigned.
  std::ifstream metrics(dir.path() / "metrics.jsonl");
  uint32_t max_epoch = 0;
  for (std::string line; std::getline(metrics, line);)
    max_epoch = std::max(max_epoch, nlohmann::json::parse(line)["epoch"].get<uint32_t>());
  EXPECT_GE(max_epoch, 1u);
}

// Interactive mode: no frame is rendered again while the inputs stay the same; an Input
// from the display moves the camera and yields exactly one new, correct frame.
TEST(InProcessFarm, InteractiveFramesFollowInputAndIdleFramesAreNotRendered) {
  FarmDir dir("interactive");
  Scene scene = smallScene(1);
  Endpoints ep = makeEndpoints("inproc://farm-interactive");
  zmq::context_t ctx;
  std::atomic<bool> stop{false};
  master::MasterOptions mo;
  mo.scene = scene;
  mo.endpoints = ep;
  mo.frames = 0;  // interactive
  renderer::StageOptions ro{scene, ep, 1};
  compositor::StageOptions co{ep, "", 512, 512, std::nullopt, sceneIdentity(scene)};
  display::StageOptions dopt{ep, (dir.path() / "out").string(), display::StageOptions::Window::Off, std::nullopt};
  dopt.scene = sceneIdentity(scene);
  std::vector<std::future<int>> stages;
  stages.push_back(std::async(std::launch::async, [&] { return master::run(mo, ctx, &stop); }));
  stages.push_back(std::async(std::launch::async, [&] { return renderer::runStage(ro, ctx, &stop); }));
  stages.push_back(std::async(std::launch::async, [&] { return compositor::runStage(co, ctx, &stop); }));
  stages.push_back(std::async(std::launch::async, [&] { return display::runStage(dopt, ctx, &stop); }));
  auto waitFor = [&](int k, std::chrono::milliseconds limit) {
    auto end = std::chrono::steady_clock::now() + limit;
    while (!fs::exists(dir.frame(k)) && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(10ms);
    return fs::exists(dir.frame(k));
  };
  EXPECT_TRUE(waitFor(0, 30s)) << "first frame missing";
  EXPECT_FALSE(waitFor(1, 500ms)) << "a frame was rendered although nothing changed";

  proto::Input in;
  in.orbit_dx = 40;
  in.zoom = 0.8;
  // The master takes Input only from a joined display: the user joins as a second one.
  StageLink user(ctx, ep, proto::Role::Display, sceneIdentity(scene));
  ASSERT_TRUE(user.join(&stop, 30));
  user.report(proto::encode(in, 0));
  EXPECT_TRUE(waitFor(1, 30s)) << "no frame after the input";
  EXPECT_FALSE(waitFor(2, 500ms)) << "more than one frame for one input";
  proto::Input home;  // the window's r: the scene's view again
  home.home = true;
  user.report(proto::encode(home, 0));
  EXPECT_TRUE(waitFor(2, 30s)) << "no frame after r";
  stop = true;
  for (auto& f : stages) {
    ASSERT_EQ(f.wait_for(30s), std::future_status::ready);
    EXPECT_EQ(f.get(), 0);
  }
  auto volume = std::make_shared<Volume>(loadVolume(scene));
  renderer::Raycaster caster(volume, scene.tf);
  renderer::RenderOptions opt;
  opt.quality = scene.quality;
  Camera moved = master::applyInput(scene.camera, in);
  Image8 ref = toRGBA8(caster.render(moved, scene.width, scene.height, renderer::wholeVolume(*volume), opt));
  Image8 before = readPng(dir.frame(0).string()), after = readPng(dir.frame(1).string());
  // 1/255: the sort-last contract.
  EXPECT_TRUE(dir.matches(after, ref, 1, "after_input"));
  EXPECT_GT(maxAbsDiff(after, before), 16) << "the camera did not move";
  EXPECT_TRUE(dir.matches(readPng(dir.frame(2).string()), before, 1, "home")) << "r did not bring back the scene's view";
}

}  // namespace
}  // namespace tessera::test
