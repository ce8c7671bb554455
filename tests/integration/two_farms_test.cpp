// Two farms on one machine never mix: each run has its own identity and, by default, its
// own socket folder; a farm cannot take over the endpoints of a live one; nothing of a
// run (socket files, an empty metrics file) is left behind.
#include <gtest/gtest.h>

#include <csignal>
#include <unistd.h>
#include <future>
#include <regex>
#include <thread>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

// The folder tessera-up said it put this run's sockets in ("" if it said none).
std::string socketFolder(const std::string& output) {
  std::smatch m;
  return std::regex_search(output, m, std::regex("run \\S+: sockets in (\\S+)")) ? m[1].str() : "";
}

// Whether `output` has a line "<endpoints>/<socket> is in use by a live farm (run '...".
bool saysInUse(const std::string& output, const std::string& endpoints) {
  const std::string prefix = endpoints + "/", in_use = " is in use by a live farm (run '";
  for (size_t at = output.find(prefix); at != std::string::npos; at = output.find(prefix, at + 1)) {
    const size_t socket_end = output.find_first_of(" \n", at);
    if (socket_end != std::string::npos && output.compare(socket_end, in_use.size(), in_use) == 0) return true;
  }
  return false;
}

void expectFramesMatch(const FarmDir& dir, const fs::path& scene, int frames) {
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing in " << dir.path();
    // 1/255: pieces are quantized to rgba8 once before compositing.
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k)));
  }
}

TEST(TwoFarms, StartedAtOnceWithDefaultSettingsBothRenderTheirOwnScene) {
  FarmDir a("two-a"), b("two-b");
  const int frames_a = 40, frames_b = 10;
  const auto scene_a = a.writeScene(frames_a, 40, 96, 80), scene_b = b.writeScene(frames_b, 24, 64, 48);
  auto run_a = std::async(std::launch::async, [&] { return a.runFarm(scene_a, 2, 1, frames_a, 120, "", "default"); });
  std::this_thread::sleep_for(300ms);  // B starts while A's stages are joining or rendering
  auto run_b = std::async(std::launch::async, [&] { return b.runFarm(scene_b, 2, 1, frames_b, 120, "", "default"); });
  const auto ra = run_a.get(), rb = run_b.get();
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  ASSERT_EQ(rb.exit_code, 0) << rb.output;
  expectFramesMatch(a, scene_a, frames_a);
  expectFramesMatch(b, scene_b, frames_b);
  const std::string folder_a = socketFolder(ra.output), folder_b = socketFolder(rb.output);
  ASSERT_FALSE(folder_a.empty()) << ra.output;
  EXPECT_NE(folder_a, folder_b) << "both runs used one socket folder";
  EXPECT_FALSE(fs::exists(folder_a)) << "run A left its socket folder";
  EXPECT_FALSE(fs::exists(folder_b)) << "run B left its socket folder";
}

TEST(TwoFarms, AFarmOnTheEndpointsOfALiveFarmRefusesToStartAndTheLiveOneGoesOn) {
  FarmDir a("live-a"), b("live-b");
  const int frames = 400;
  const auto scene = a.writeScene(frames, 40, 96, 80);
  const std::string shared = "ipc://" + (a.path() / "sockets").string();
  auto run_a = std::async(std::launch::async, [&] { return a.runFarm(scene, 1, 1, frames, 180, "", shared); });
  bool seen = false;
  for (int i = 0; i < 1500 && !(seen = fs::exists(a.frame(1))); ++i) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(seen) << "farm A produced no frame\n" << a.farmLog();
  const auto rb = b.runFarm(b.writeScene(5, 24, 64, 48), 1, 1, 5, 60, "", shared);
  const bool a_still_running = !fs::exists(a.frame(frames - 1));
  EXPECT_NE(rb.exit_code, 0) << rb.output;
  // Whichever of B's stages binds first says so (the display often does, before the master
  // has read its scene); tessera-up then stops the others.
  EXPECT_TRUE(saysInUse(rb.output, shared)) << rb.output;
  EXPECT_FALSE(fs::exists(b.path() / "out" / "metrics.jsonl")) << "the failed start left a metrics file";
  const auto ra = run_a.get();
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  ASSERT_TRUE(a_still_running) << "farm A was done before B tried: the test proves nothing";
  EXPECT_EQ(ra.output.find("joined pid", ra.output.find("frame 2 of")), std::string::npos)
      << "a stage joined farm A after it started rendering:\n" << ra.output;
  expectFramesMatch(a, scene, frames);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(a.path() / "sockets")) left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << "left in the socket folder: " << left.size() << " entries, first " << left.front();
}

// A second farm given the live one's TESSERA_RUN (so the same default socket folder) is
// refused, and its failed start must not take that folder away: it did, and a third farm of
// the run then started on the live farm's endpoints and took its restarted stages (found by
// review).
TEST(TwoFarms, AFailedStartOfTheSameRunLeavesTheLiveFarmsSockets) {
  FarmDir a("run-a"), b("run-b");
  const int frames = 400;
  const auto scene = a.writeScene(frames, 40, 96, 80);
  const std::string run = "--env TESSERA_RUN=shared" + std::to_string(::getpid());
  auto run_a = std::async(std::launch::async, [&] { return a.runFarm(scene, 1, 1, frames, 180, run, "default"); });
  bool seen = false;
  for (int i = 0; i < 1500 && !(seen = fs::exists(a.frame(1))); ++i) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(seen) << "farm A produced no frame\n" << a.farmLog();
  const std::string folder = socketFolder(a.farmLog());
  ASSERT_FALSE(folder.empty()) << a.farmLog();
  const auto rb = b.runFarm(b.writeScene(5, 24, 64, 48), 1, 1, 5, 60, run, "default");
  const bool a_still_running = !fs::exists(a.frame(frames - 1));
  EXPECT_NE(rb.exit_code, 0) << rb.output;
  EXPECT_TRUE(saysInUse(rb.output, "ipc://" + folder)) << rb.output;
  EXPECT_TRUE(fs::exists(folder)) << "the refused farm removed the live farm's socket folder " << folder;
  const auto ra = run_a.get();
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  ASSERT_TRUE(a_still_running) << "farm A was done before B tried: the test proves nothing";
  EXPECT_FALSE(fs::exists(folder)) << "farm A left its socket folder";
}

// Two farms writing one output folder would overwrite each other's frames and splice their
// metrics.jsonl lines (seen by a new user): the second refuses, naming the folder and the first.
TEST(TwoFarms, ASecondFarmOnTheSameOutputFolderRefusesAndTheFirstGoesOn) {
  FarmDir a("out-a"), b("out-b");
  const int frames = 30;
  const auto scene = a.writeScene(frames, 40, 96, 80);
  auto run_a = std::async(std::launch::async, [&] { return a.runFarm(scene, 2, 1, frames); });
  // B starts once A is running (its first frame is out), on A's output folder.
  for (int i = 0; i < 600 && !fs::exists(a.frame(0)); ++i) std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(fs::exists(a.frame(0))) << "farm A never rendered";
  const auto rb = b.runFarm(scene, 1, 1, 2, 60, "--env TESSERA_OUT=" + (a.path() / "out").string());
  EXPECT_NE(rb.exit_code, 0) << rb.output;
  EXPECT_NE(rb.output.find("output folder " + (a.path() / "out").string() + " is in use by another farm (tessera-up pid "),
            std::string::npos) << rb.output;
  const auto ra = run_a.get();
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  expectFramesMatch(a, scene, frames);
  EXPECT_FALSE(fs::exists(a.path() / "out" / ".tessera-farm")) << "farm A left its lock file";
}

TEST(TwoFarms, CtrlCLeavesNoSocketBehind) {
  FarmDir dir("ctrl-c");
  const auto scene = dir.writeScene(1, 24, 64, 48);
  // An interactive run (frames 0) waits for input until stopped; timeout sends the Ctrl-C.
  const auto r = runCommand("timeout --preserve-status -s INT 4 " + bin("tessera-up") + " " TESSERA_SOURCE_DIR
                            "/compose.yaml --env TESSERA_SCENE=" + scene.string() + " --env TESSERA_FRAMES=0" +
                                " --env TESSERA_WINDOW=off --env TESSERA_OUT=" + (dir.path() / "out").string(),
                            60);
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.output;
  const std::string folder = socketFolder(r.output);
  ASSERT_FALSE(folder.empty()) << r.output;
  EXPECT_FALSE(fs::exists(folder)) << "Ctrl-C left the socket folder " << folder;
  EXPECT_TRUE(fs::exists(dir.frame(0))) << "the farm never rendered: the test proves nothing\n" << r.output;
}

}  // namespace
}  // namespace tessera::test
