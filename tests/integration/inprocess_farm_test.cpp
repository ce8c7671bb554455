// The whole farm inside one process over inproc:// (the transport the stages share with
// ipc:// and tcp://): a renderer that vanishes mid-run is detected by heartbeat, its
// bricks are reassigned under a new epoch, and every frame still matches the one-process
// render.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <optional>
#include <fstream>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/io/image_io.h"
#include "common/net/stage_link.h"
#include "compositor/stage.h"
#include "display/stage.h"
#include "tests/integration/farm_util.h"
#include "master/interaction.h"
#include "master/master.h"
#include "master/refinement.h"
#include "common/max_intensity.h"
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

// An interactive farm in this process (master, renderers, one compositor, a display writing
// PNG files) and a user who joins as a second display to send Input.
class InteractiveFarm {
 public:
  InteractiveFarm(FarmDir& dir, const Scene& scene, int renderers, const std::string& name, bool binary_swap = false)
      : dir_(dir), scene_(scene), ep_(makeEndpoints("inproc://" + name)) {
    mo_.scene = scene;
    mo_.binary_swap = binary_swap;
    mo_.metrics_path = (dir.path() / "metrics.jsonl").string();
    mo_.endpoints = ep_;
    mo_.frames = 0;  // interactive
    mo_.renderers = renderers;
    for (int r = 0; r < renderers; ++r) ro_.push_back({scene, ep_, 1});  // one thread each
    co_ = {ep_, "", 512, 512, std::nullopt, sceneIdentity(scene)};
    if (isProjection(scene.blend)) co_.maximum = scene.tf, co_.minimum = scene.blend == Blend::Minimum;
    dopt_ = {ep_, (dir.path() / "out").string(), display::StageOptions::Window::Off, std::nullopt};
    dopt_.scene = sceneIdentity(scene);
    stages_.push_back(std::async(std::launch::async, [&] { return master::run(mo_, ctx_, &stop_); }));
    for (auto& ro : ro_) stages_.push_back(std::async(std::launch::async, [&] { return renderer::runStage(ro, ctx_, &stop_); }));
    stages_.push_back(std::async(std::launch::async, [&] { return compositor::runStage(co_, ctx_, &stop_); }));
    stages_.push_back(std::async(std::launch::async, [&] { return display::runStage(dopt_, ctx_, &stop_); }));
  }
  ~InteractiveFarm() { stop_ = true; }

  bool waitFor(int k, std::chrono::milliseconds limit) {
    auto end = std::chrono::steady_clock::now() + limit;
    while (!fs::exists(dir_.frame(k)) && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(10ms);
    return fs::exists(dir_.frame(k));
  }
  // The master takes Input only from a joined display: the user joins as a second one.
  void send(const proto::Input& in) {
    if (!user_) {
      user_.emplace(ctx_, ep_, proto::Role::Display, sceneIdentity(scene_));
      ASSERT_TRUE(user_->join(&stop_, 30));
    }
    user_->report(proto::encode(in, 0));
  }
  void stop() {
    stop_ = true;
    for (auto& f : stages_) {
      ASSERT_EQ(f.wait_for(30s), std::future_status::ready);
      EXPECT_EQ(f.get(), 0);
    }
  }

 private:
  FarmDir& dir_;
  Scene scene_;
  Endpoints ep_;
  zmq::context_t ctx_;
  std::atomic<bool> stop_{false};
  master::MasterOptions mo_;
  std::vector<renderer::StageOptions> ro_;
  compositor::StageOptions co_;
  display::StageOptions dopt_;
  std::vector<std::future<int>> stages_;
  std::optional<StageLink> user_;
};

// Each frame's line of the master's metrics.jsonl.
std::vector<nlohmann::json> frameLines(const FarmDir& dir) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(dir.path() / "metrics.jsonl");
  for (std::string line; std::getline(in, line);)
    if (auto j = nlohmann::json::parse(line, nullptr, false); j.is_object() && j.contains("frame")) lines.push_back(j);
  return lines;
}

// The one-process render of `scene` seen by `cam` through colour window `w`.
Image8 windowedRender(const Scene& scene, const Camera& cam, const ColorWindow& w) {
  auto volume = std::make_shared<Volume>(loadVolume(scene));
  const TransferFunction tf = windowed(scene.tf, w);
  renderer::Raycaster caster(volume, tf, {}, {0, 0, 0}, scene.blend);
  renderer::RenderOptions opt;
  opt.quality = scene.quality;
  ImageF img = caster.render(cam, scene.width, scene.height, renderer::wholeVolume(*volume), opt);
  if (isProjection(scene.blend))
    MaxIntensity(tf, scene.blend == Blend::Minimum).map(img.px.data(), (size_t)img.width * img.height);
  return toRGBA8(img);
}

// Interactive mode: no frame is rendered again while the inputs stay the same; an Input
// from the display moves the camera and yields exactly one new, correct frame; a right-drag's
// colour window too; r brings back the scene's view and colours.
TEST(InProcessFarm, InteractiveFramesFollowInputAndIdleFramesAreNotRendered) {
  FarmDir dir("interactive");
  Scene scene = smallScene(1);
  InteractiveFarm farm(dir, scene, 1, "farm-interactive");
  EXPECT_TRUE(farm.waitFor(0, 30s)) << "first frame missing";
  EXPECT_FALSE(farm.waitFor(1, 500ms)) << "a frame was rendered although nothing changed";
  proto::Input in;
  in.orbit_dx = 40;
  in.zoom = 0.8;
  farm.send(in);
  EXPECT_TRUE(farm.waitFor(1, 30s)) << "no frame after the input";
  EXPECT_FALSE(farm.waitFor(2, 500ms)) << "more than one frame for one input";
  proto::Input window;  // a right drag's sum, released
  window.window_shift = 0.4;
  window.window_scale = 0.5;
  farm.send(window);
  EXPECT_TRUE(farm.waitFor(2, 30s)) << "no frame after the colour window moved";
  proto::Input home;  // the window's r: the scene's view again
  home.home = true;
  farm.send(home);
  EXPECT_TRUE(farm.waitFor(3, 30s)) << "no frame after r";
  farm.stop();
  const Camera moved = master::applyInput(scene.camera, in);
  const ColorWindow w = master::Refinement::movedWindow({}, 0.4, 0.5);
  Image8 before = readPng(dir.frame(0).string()), after = readPng(dir.frame(1).string());
  // 1/255: the sort-last contract.
  EXPECT_TRUE(dir.matches(after, windowedRender(scene, moved, {}), 1, "after_input"));
  EXPECT_GT(maxAbsDiff(after, before), 16) << "the camera did not move";
  const Image8 recoloured = readPng(dir.frame(2).string());
  EXPECT_TRUE(dir.matches(recoloured, windowedRender(scene, moved, w), 1, "window"));
  EXPECT_GT(maxAbsDiff(recoloured, after), 16) << "the colour window did not change the image";
  EXPECT_TRUE(dir.matches(readPng(dir.frame(3).string()), before, 1, "home")) << "r did not bring back the scene's view";
}

// The intensity projections map the merged values once, where the frame is finished (the
// compositor with direct send, the renderers' bands with binary swap): through the frame's
// colour window, and for the minimum projection the window's map mirrored (the window first).
// The minimum projection's volume has no empty space (every ray's smallest value would be 0):
// the Marschner-Lobb volume, with a map opaque below 0.5.
TEST(InProcessFarm, AColourWindowRecoloursAnIntensityProjectionFarm) {
  for (const auto& [blend, binary_swap] : {std::pair{Blend::Maximum, false}, std::pair{Blend::Maximum, true},
                                           std::pair{Blend::Minimum, false}, std::pair{Blend::Minimum, true}}) {
    SCOPED_TRACE(std::string(blendName(blend)) + (binary_swap ? ", binary swap" : ", direct send"));
    const std::string name = std::string("interactive-") + (blend == Blend::Maximum ? "mip" : "minip") +
                             (binary_swap ? "-swap" : "");
    FarmDir dir(name);
    Scene scene = smallScene(1);
    scene.blend = blend;
    if (blend == Blend::Minimum) {
      scene.volume = GeneratorSpec{"marschner-lobb", 32, 1};
      scene.tf = TransferFunction({{0, 1, 1, 0.8, 1}, {0.15, 1, 0.6, 0.1, 1}, {0.3, 0.1, 0.2, 0.9, 0.6},
                                   {0.5, 0, 0, 0, 0}, {1, 0, 0, 0, 0}});
    }
    InteractiveFarm farm(dir, scene, 2, "farm-" + name, binary_swap);
    EXPECT_TRUE(farm.waitFor(0, 30s)) << "first frame missing";
    proto::Input window;
    window.window_shift = -0.3;
    window.window_scale = 0.4;
    farm.send(window);
    EXPECT_TRUE(farm.waitFor(1, 30s)) << "no frame after the colour window moved";
    farm.stop();
    const ColorWindow w = master::Refinement::movedWindow({}, -0.3, 0.4);
    const Image8 before = readPng(dir.frame(0).string()), after = readPng(dir.frame(1).string());
    EXPECT_TRUE(dir.matches(before, windowedRender(scene, scene.camera, {}), 1, "mip"));
    EXPECT_TRUE(dir.matches(after, windowedRender(scene, scene.camera, w), 1, "mip_window"));
    // The frame's line in metrics.jsonl gives its window; tessera-render --window renders it so.
    const auto lines = frameLines(dir);
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_EQ(lines[1]["window"], nlohmann::json::array({w.center, w.width}));
    const fs::path file = dir.path() / "mip.yaml";
    std::ofstream(file) << sceneYaml(scene);
    const std::string arg = fmt::format("--window {},{}", lines[1]["window"][0].get<double>(), lines[1]["window"][1].get<double>());
    EXPECT_TRUE(dir.matches(after, dir.reference(file, 0, arg), 1, "mip_tessera_render_window"));
    EXPECT_GT(maxAbsDiff(after, before), 16) << "the colour window did not change the image";
  }
}

}  // namespace
}  // namespace tessera::test
