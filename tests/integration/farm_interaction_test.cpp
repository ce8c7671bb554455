// The window as people use it: the real farm (tessera-up on compose.yaml, interactive) with
// its window on a private Xvfb, driven by a real mouse and keyboard through XTEST. Assertions
// are on events and counts (metrics.jsonl) and on the pixels on screen, never on wall time:
// the latency figures live in tessera-interaction-bench.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <future>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "tests/display/xvfb.h"
#include "tests/integration/farm_util.h"
#include "tests/display/xtest.h"  // last: Xlib's macros

namespace tessera::test {
namespace {

using namespace std::chrono_literals;
using display::testing::XUser;

constexpr int kW = 320, kH = 240;

std::vector<nlohmann::json> metricsLines(const FarmDir& dir) {
  std::ifstream in(dir.path() / "out" / "metrics.jsonl");
  std::vector<nlohmann::json> lines;
  for (std::string l; std::getline(in, l);)
    if (!l.empty()) lines.push_back(nlohmann::json::parse(l));
  return lines;
}

template <class F>
bool waitUntil(F ok, std::chrono::milliseconds limit) {
  for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
    if (ok()) return true;
    std::this_thread::sleep_for(50ms);
  }
  return ok();
}

// The farm on a private X server, its window found and the first frame shown.
class FarmInteraction : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!display::testing::onPath("Xvfb")) GTEST_SKIP() << "Xvfb not installed (Debian package xvfb)";
    std::string err;
    ASSERT_TRUE(xvfb_.start(err)) << err;
    setenv("DISPLAY", xvfb_.display().c_str(), 1);
    unsetenv("WAYLAND_DISPLAY");
    user_ = std::make_unique<XUser>(xvfb_.display());
    ASSERT_TRUE(user_->ok()) << "no XTEST on " << xvfb_.display();
    scene_ = dir_.path() / "scene.yaml";
    std::ofstream(scene_) << sceneText();
    farm_ = std::async(std::launch::async, [&] { return dir_.runFarm(scene_, 2, 1, 0, 200, "--env TESSERA_WINDOW=on"); });
    ASSERT_TRUE(waitUntil([&] { return (win_ = user_->find("Tessera")) && !metricsLines(dir_).empty(); }, 90s))
        << dir_.farmLog();
  }
  // A cloud of noise, not the symmetric shell: turning it changes the picture.
  virtual std::string sceneText() const {
    std::ostringstream s;
    s << "volume:\n  generator: {name: noise-cloud, size: 48, seed: 7}\n"
                          << "transfer_function:\n  - [0.00, 0.6, 0.7, 0.9, 0.0]\n  - [0.03, 0.6, 0.7, 0.9, 0.0]\n"
                          << "  - [0.10, 0.6, 0.7, 0.9, 0.05]\n  - [0.40, 0.9, 0.9, 1.0, 0.2]\n  - [1.00, 1.0, 1.0, 1.0, 0.6]\n"
                          << "camera: {eye: [1.6, 0.8, 1.6], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                          << "image: [" << kW << ", " << kH << "]\nquality: default\n";
    return s.str();
  }
  void TearDown() override {
    if (farm_.valid()) {
      if (user_) user_->key(XK_Escape);  // the user closes the farm from its window
      if (farm_.wait_for(60s) == std::future_status::ready) {
        auto r = farm_.get();
        EXPECT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("display finished; stopping the farm"), std::string::npos) << r.output;
      } else {
        ADD_FAILURE() << "the farm did not stop after Esc";
      }
    }
    unsetenv("DISPLAY");
  }
  // The newest metrics line that shows input `after` frame `frame` and is sharp.
  std::optional<nlohmann::json> sharpAfter(uint64_t frame) {
    std::optional<nlohmann::json> found;
    for (auto& l : metricsLines(dir_))
      if (l["frame"].get<uint64_t>() > frame && !l["interactive"].get<bool>()) found = l;
    return found;
  }
  int centreX() const { return win_->x + win_->width / 2; }
  int centreY() const { return win_->y + win_->height / 2; }

  display::testing::Xvfb xvfb_;
  std::unique_ptr<XUser> user_;
  FarmDir dir_{"interaction"};
  fs::path scene_;
  std::future<CommandResult> farm_;
  std::optional<XUser::Geometry> win_;
};

TEST_F(FarmInteraction, ADragShowsReducedFramesThenTheSharpFrameOfTheFinalCamera) {
  const auto first = metricsLines(dir_).front();
  EXPECT_FALSE(first["interactive"].get<bool>());
  std::string err;
  std::this_thread::sleep_for(300ms);  // the first frame on screen
  const Image8 before = display::testing::screenshotRoot(xvfb_.display(), err);
  ASSERT_FALSE(before.px.empty()) << err;
  user_->drag(centreX(), centreY(), 4, 1, 30, 20ms);
  const uint64_t last_before = metricsLines(dir_).back()["frame"].get<uint64_t>();
  std::optional<nlohmann::json> sharp;
  ASSERT_TRUE(waitUntil([&] { return (sharp = sharpAfter(0)).has_value(); }, 60s)) << dir_.farmLog();
  const auto lines = metricsLines(dir_);
  int interactive = 0;
  for (const auto& l : lines)
    if (l["interactive"].get<bool>()) {
      ++interactive;
      // Reduced in size only when that is needed to keep up: this small scene may not need it.
      EXPECT_LE(l["width"].get<int>(), kW);
      EXPECT_GT(l["input_ms"].get<double>(), 0) << "it shows new input";
    }
  EXPECT_GE(interactive, 1) << "no reduced frame while the mouse moved";
  std::ifstream doc_in(std::string(TESSERA_SOURCE_DIR) + "/docs/metrics.md");  // every field explained
  const std::string doc(std::istreambuf_iterator<char>(doc_in), {});
  for (const auto& [key, value] : lines.back().items()) EXPECT_NE(doc.find("`" + key + "`"), std::string::npos) << key;
  EXPECT_EQ(sharp->at("width").get<int>(), kW);
  EXPECT_NE(sharp->at("camera"), first["camera"]) << "the drag did not move the camera";
  EXPECT_GE(sharp->at("frame").get<uint64_t>(), last_before);

  // What the user sees once the mouse stops: tessera-render of the final camera, composited
  // over the window's background, within the farm's 1-level contract.
  const auto& c = sharp->at("camera");
  const fs::path final_scene = dir_.path() / "final.yaml";
  {
    std::ifstream in(scene_);
    std::ofstream out(final_scene);
    for (std::string l; std::getline(in, l);)
      if (l.rfind("camera:", 0) != 0) out << l << "\n";
    out.precision(17);
    out << "camera: {eye: " << c["eye"].dump() << ", target: " << c["target"].dump() << ", up: " << c["up"].dump()
        << ", fov: " << c["fov"].get<double>() << "}\n";
  }
  const Image8 ref = dir_.reference(final_scene, 0);
  Image8 shot, want(kW, kH / 2), got(kW, kH / 2), was(kW, kH / 2);
  const int bg[3] = {32, 32, 36};
  // The top half (the status strip wraps over the bottom at this width). The screen may lag a
  // moment behind the metrics line: look again, bounded.
  for (int attempt = 0; attempt < 20 && (attempt == 0 || maxAbsDiff(got, want) > 1); ++attempt) {
    std::this_thread::sleep_for(200ms);
    shot = display::testing::screenshotRoot(xvfb_.display(), err);
    ASSERT_FALSE(shot.px.empty()) << err;
    for (int y = 0; y < kH / 2; ++y)
      for (int x = 0; x < kW; ++x) {
        const uint8_t* r = ref.at(x, y);
        const uint8_t* s = shot.at(win_->x + x, win_->y + y);
        for (int ch = 0; ch < 3; ++ch) {
          want.at(x, y)[ch] = (uint8_t)std::min(255, r[ch] + (bg[ch] * (255 - r[3]) + 127) / 255);
          got.at(x, y)[ch] = s[ch];
          was.at(x, y)[ch] = before.at(win_->x + x, win_->y + y)[ch];
        }
        want.at(x, y)[3] = got.at(x, y)[3] = was.at(x, y)[3] = 255;
      }
  }
  EXPECT_TRUE(dir_.matches(got, want, 1, "sharp_frame_on_screen"));
  EXPECT_GT(maxAbsDiff(got, was), 16) << "the drag did not change the picture";
}

TEST_F(FarmInteraction, ABurstOfMotionIssuesFewFramesAndAResizeRendersAtTheNewSize) {
  const uint64_t before = metricsLines(dir_).size();
  user_->drag(centreX(), centreY(), 1, 0, 200, 0ms);  // 200 motion events at once
  std::optional<nlohmann::json> sharp;
  ASSERT_TRUE(waitUntil([&] { return (sharp = sharpAfter(0)).has_value(); }, 60s)) << dir_.farmLog();
  std::this_thread::sleep_for(500ms);  // anything still on its way
  const auto lines = metricsLines(dir_);
  EXPECT_LE(lines.size() - before, 20u) << "200 motion events must coalesce, not queue frames";
  for (const auto& l : lines) EXPECT_LE(l["latency_ms"].get<double>(), 30000);

  user_->resize(win_->window, 200, 150);
  std::optional<nlohmann::json> resized;
  ASSERT_TRUE(waitUntil(
      [&] {
        for (const auto& l : metricsLines(dir_))
          if (!l["interactive"].get<bool>() && l["width"].get<int>() == 200 && l["height"].get<int>() == 150) return true;
        return false;
      },
      60s))
      << "no sharp frame at the window's new size; " << dir_.farmLog();
}

// A time series in the window: the arrows step, End and Home jump, Space plays and pauses;
// each takes effect on the next frame (metrics say which step every frame showed).
class FarmTimeKeys : public FarmInteraction {
 protected:
  std::string sceneText() const override {
    return "volume:\n  generator: {name: moving-blobs, size: 24, steps: 10}\nimage: [160, 120]\ntime: {play: false, step: 3}\n";
  }
  // Whether a frame after `frame` shows `step`; the newest frame's number goes to `frame`.
  bool shows(int step, uint64_t& frame) {
    return waitUntil([&] {
      for (auto& l : metricsLines(dir_))
        if (l["frame"].get<uint64_t>() > frame && l["step"].get<int>() == step) return frame = l["frame"].get<uint64_t>(), true;
      return false;
    }, 30s);
  }
};

TEST_F(FarmTimeKeys, ArrowsHomeEndAndSpaceMoveThroughTheSteps) {
  uint64_t frame = 0;
  EXPECT_EQ(metricsLines(dir_).front()["step"], 3) << "the scene's time.step";
  user_->key(XK_Right);
  ASSERT_TRUE(shows(4, frame)) << dir_.farmLog();
  user_->key(XK_Left);
  std::this_thread::sleep_for(100ms);  // two presses, not one press seen as its auto-repeat
  user_->key(XK_Left);
  ASSERT_TRUE(shows(2, frame));
  user_->key(XK_End);
  ASSERT_TRUE(shows(9, frame));
  user_->key(XK_space);  // play: on through the last step to the first again
  ASSERT_TRUE(shows(0, frame));
  ASSERT_TRUE(shows(1, frame));
  user_->key(XK_space);  // pause: frames stop
  std::this_thread::sleep_for(500ms);
  const size_t paused = metricsLines(dir_).size();
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(metricsLines(dir_).size(), paused) << "no frames while paused";
  uint64_t after = metricsLines(dir_).back()["frame"].get<uint64_t>();
  if (metricsLines(dir_).back()["step"].get<int>() == 0) {  // the small steps play fast: it may have wrapped to 0
    user_->key(XK_Right);
    ASSERT_TRUE(shows(1, after));
  }
  user_->key(XK_Home);  // from a step other than the first: Home must show the first
  ASSERT_TRUE(shows(0, after));
}

}  // namespace
}  // namespace tessera::test
