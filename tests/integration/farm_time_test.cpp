// Time series on the farm: a played series equals tessera-render --step of each frame's step
// for 1, 2 and 3 renderers; playing backwards, swinging and jumping show the same frames as
// playing forwards; a missing or cut-short step is named, counted and skipped (the last good
// step shown) while the farm goes on; renderers read each step's bricks once and stay within
// their cache budget.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <limits>
#include <map>
#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

constexpr int kSteps = 20;

// moving-blobs over kSteps steps, a fixed camera, plus `time`.
fs::path writeSeriesScene(const FarmDir& dir, const std::string& name, const std::string& time, int size = 24) {
  const fs::path p = dir.path() / name;
  std::ofstream(p) << "volume:\n  generator: {name: moving-blobs, size: " << size << ", steps: " << kSteps << "}\n"
                   << "transfer_function:\n  - [0.0, 0.0, 0.0, 0.0, 0.0]\n  - [0.2, 0.2, 0.5, 1.0, 0.1]\n"
                   << "  - [1.0, 1.0, 0.8, 0.3, 0.9]\n"
                   << "camera: {eye: [0.4, 0.6, 2.0], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                   << "image: [64, 48]\nquality: default\ntime: " << time << "\n";
  return p;
}

std::vector<nlohmann::json> metrics(const FarmDir& dir) {
  std::vector<nlohmann::json> out;
  std::ifstream in(dir.path() / "out" / "metrics.jsonl");
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a["frame"] < b["frame"]; });
  return out;
}

TEST(FarmTime, PlayedFramesEqualOneProcessOfTheirStepForOneTwoThreeRenderers) {
  FarmDir dir("time-play");
  const fs::path scene = writeSeriesScene(dir, "play.yaml", "{play: true}");
  std::map<int, Image8> refs;
  for (int s = 0; s < kSteps; ++s) refs[s] = dir.reference(scene, 0, "--step " + std::to_string(s));
  for (int renderers : {1, 2, 3}) {
    const auto r = dir.runFarm(scene, renderers, 1, kSteps);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto m = metrics(dir);
    ASSERT_EQ(m.size(), (size_t)kSteps) << r.output;
    for (int k = 0; k < kSteps; ++k) {
      EXPECT_EQ(m[k]["step"], k) << "frame " << k;
      EXPECT_TRUE(dir.matches(dir.farmFrame(k), refs[k], 1, std::to_string(renderers) + "r_frame_" + std::to_string(k)));
    }
    // Each renderer looked up every frame's step once; prefetching served some (how many is
    // the benchmark's question: tests/bench/time_series_bench.sh).
    const auto& last = m.back();
    EXPECT_EQ(last["render_step_hits"].get<int>() + last["render_step_misses"].get<int>(), kSteps * renderers) << r.output;
    EXPECT_GE(last["render_step_hits"].get<int>(), 1) << r.output;
  }
}

TEST(FarmTime, BackwardsSwingAndJumpsShowWhatPlayingForwardsShows) {
  FarmDir dir("time-orders");
  auto run = [&](const std::string& time, int frames) {
    const fs::path scene = writeSeriesScene(dir, "s.yaml", time);
    const auto r = dir.runFarm(scene, 2, 1, frames);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::map<int, Image8> byStep;
    const auto m = metrics(dir);
    EXPECT_EQ(m.size(), (size_t)frames) << r.output;
    for (size_t k = 0; k < m.size(); ++k) byStep[m[k]["step"].get<int>()] = dir.farmFrame((int)k);
    return byStep;
  };
  const auto forward = run("{play: true}", kSteps);
  ASSERT_EQ(forward.size(), (size_t)kSteps);
  struct Case {
    std::string time;
    int frames;
    std::vector<int> first_steps;
  };
  const Case cases[] = {{"{play: true, stride: -1, step: 19}", kSteps, {19, 18, 17}},
                        {"{play: true, mode: swing, stride: 3}", 14, {0, 3, 6}},
                        {"{play: true, stride: 7, step: 5}", kSteps, {5, 12, 19}}};
  for (const auto& c : cases) {
    const auto shown = run(c.time, c.frames);
    const auto m = metrics(dir);
    for (size_t i = 0; i < c.first_steps.size() && i < m.size(); ++i) EXPECT_EQ(m[i]["step"], c.first_steps[i]) << c.time;
    for (const auto& [step, image] : shown)
      EXPECT_TRUE(dir.matches(image, forward.at(step), 0, "step_" + std::to_string(step))) << c.time;
  }
}

TEST(FarmTime, AMissingOrShortStepIsNamedCountedAndSkipped) {
  FarmDir dir("time-bad-step");
  auto w = runCommand(bin("tessera-write-series") + " " + (dir.path() / "data").string() +
                          " --size 24 --steps 8 --formats raw", 60);
  ASSERT_EQ(w.exit_code, 0) << w.output;
  fs::remove(dir.path() / "data" / "step_00003.raw");
  fs::resize_file(dir.path() / "data" / "step_00005.raw", 1000);
  const fs::path scene = dir.path() / "data" / "series-raw.yaml";
  std::ofstream(scene, std::ios::app) << "image: [64, 48]\ncamera: {eye: [0.4, 0.6, 2.0], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n";
  const auto r = dir.runFarm(scene, 2, 1, 8);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find((dir.path() / "data" / "step_00003.raw").string() + ": file not found; showing step 2"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("step_00005.raw: file size is 1000 bytes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bad steps: 2"), std::string::npos) << r.output;
  for (int k = 0; k < 8; ++k) ASSERT_TRUE(fs::exists(dir.frame(k))) << k;
  // The last good step stands in: frame 3 shows step 2, frame 5 step 4.
  EXPECT_TRUE(dir.matches(dir.farmFrame(3), dir.farmFrame(2), 0, "bad_3"));
  EXPECT_TRUE(dir.matches(dir.farmFrame(5), dir.farmFrame(4), 0, "bad_5"));
  EXPECT_TRUE(dir.matches(dir.farmFrame(6), dir.reference(scene, 0, "--step 6"), 1, "after_bad"));
  // The metrics say the step shown, and the one asked for (they said 3 and 5: found by review).
  const auto m = metrics(dir);
  ASSERT_EQ(m.size(), 8u);
  for (int k : {3, 5}) {
    EXPECT_EQ(m[k]["step"], k - 1) << "frame " << k;
    EXPECT_EQ(m[k]["step_asked"], k) << "frame " << k;
  }
  EXPECT_EQ(m[6]["step"], 6);
  EXPECT_FALSE(m[6].contains("step_asked"));
}

// A step bad in one renderer's bricks only (a NaN there): that renderer shows its last good
// step while the other shows the step, so the frame mixes two steps (metrics: steps_shown).
// From then on every renderer is asked for the stand-in, so the next pass shows one step
// (it mixed on every pass: found by review).
TEST(FarmTime, AStepBadInOneRenderersBricksMixesOneFrameOnly) {
  FarmDir dir("time-bad-brick");
  auto w = runCommand(bin("tessera-write-series") + " " + (dir.path() / "data").string() +
                          " --size 24 --steps 8 --formats raw", 60);
  ASSERT_EQ(w.exit_code, 0) << w.output;
  {
    std::fstream f(dir.path() / "data" / "step_00003.raw", std::ios::in | std::ios::out | std::ios::binary);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    f.write(reinterpret_cast<const char*>(&nan), 4);  // voxel (0, 0, 0): in one renderer's bricks
  }
  const fs::path scene = dir.path() / "data" / "series-raw.yaml";
  std::ofstream(scene, std::ios::app) << "image: [64, 48]\ncamera: {eye: [0.4, 0.6, 2.0], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n";
  const auto r = dir.runFarm(scene, 2, 1, 24);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("non-finite value nan at voxel (0, 0, 0)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame 3 showed steps 2 and 3 together"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("from now on every renderer shows step 2 in its place"), std::string::npos) << r.output;
  const auto m = metrics(dir);
  ASSERT_EQ(m.size(), 24u);
  EXPECT_EQ(m[3]["steps_shown"], nlohmann::json::array({2, 3})) << m[3];
  // The third pass: frame 3's metrics (its last Stats may lag) are in long before.
  EXPECT_FALSE(m[19].contains("steps_shown")) << m[19];
  EXPECT_EQ(m[19]["step"], 2) << m[19];
  EXPECT_EQ(m[19]["step_asked"], 3) << m[19];
  EXPECT_TRUE(dir.matches(dir.farmFrame(19), dir.reference(scene, 0, "--step 2"), 1, "stand_in"));
  EXPECT_TRUE(dir.matches(dir.farmFrame(20), dir.reference(scene, 0, "--step 4"), 1, "after_stand_in"));
}

// A gzip 4-D file's steps are read through one stream per renderer (forwards: one step's
// decompression each): swinging forwards and back shows what one process renders of each step.
TEST(FarmTime, AGzippedFourDFileSwingsThroughOneStreamAsOneProcessRendersIt) {
  FarmDir dir("time-gzip");
  auto w = runCommand(bin("tessera-write-series") + " " + (dir.path() / "data").string() +
                          " --size 24 --steps 6 --type uint16 --formats nifti && gzip -1 " + (dir.path() / "data" / "series.nii").string(),
                      60);
  ASSERT_EQ(w.exit_code, 0) << w.output;
  const fs::path scene = dir.path() / "data" / "gz.yaml";
  std::ofstream(scene) << "volume: {file: series.nii.gz, range: [0, 65535]}\ntime: {play: true, mode: swing}\n"
                       << "image: [64, 48]\ncamera: {eye: [0.4, 0.6, 2.0], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n";
  const auto r = dir.runFarm(scene, 2, 1, 10);  // steps 0 1 2 3 4 5 4 3 2 1
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m = metrics(dir);
  ASSERT_EQ(m.size(), 10u) << r.output;
  for (int k = 0; k < 10; ++k) {
    const int step = k <= 5 ? k : 10 - k;
    EXPECT_EQ(m[k]["step"], step) << "frame " << k;
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, 0, "--step " + std::to_string(step)), 1,
                            "gz_frame_" + std::to_string(k)));
  }
  EXPECT_EQ(r.output.find("instead (bad steps"), std::string::npos) << r.output;  // no step failed to read
  // One stream: a renderer decompresses the file's 6 steps about once (the steps swung back
  // to are in its cache). A stream opened for every step would decompress 0 + 1 + ... + 5
  // steps before the ones it reads: 21 steps, 0.55 MiB.
  const double file_mib = 6 * 24 * 24 * 24 * 2 / 1048576.0;
  const std::regex line(R"(read [0-9.]+ MiB of volume samples \(([0-9.]+) MiB decompressed\))");
  int renderers = 0;
  for (auto it = std::sregex_iterator(r.output.begin(), r.output.end(), line); it != std::sregex_iterator(); ++it, ++renderers)
    EXPECT_LE(std::stod((*it)[1].str()), 1.25 * file_mib + 0.005) << r.output;
  EXPECT_EQ(renderers, 2) << r.output;
}

TEST(FarmTime, EachStepIsReadOnceWithinTheCacheBudget) {
  FarmDir dir("time-budget");
  constexpr int kSize = 128, kBudgetMiB = 12, kFrames = 24;
  auto w = runCommand(bin("tessera-write-series") + " " + (dir.path() / "data").string() + " --size " +
                          std::to_string(kSize) + " --steps 12 --formats raw", 60);
  ASSERT_EQ(w.exit_code, 0) << w.output;
  auto scene = [&](const std::string& name, const std::string& time) {
    const fs::path p = dir.path() / name;
    std::ofstream(p) << "volume:\n  series: {pattern: data/step_%05d.raw, first: 0, last: 11}\n"
                     << "  dims: [" << kSize << ", " << kSize << ", " << kSize << "]\n  type: float32\n  range: [0, 1]\n"
                     << "image: [64, 48]\ntime: " << time << "\norbit: {frames: " << kFrames << ", degrees: 0}\n";
    return p;
  };
  // Peak memory per renderer, from their exit lines.
  auto peaks = [](const std::string& log) {
    const std::regex peak(R"(renderer[^|\n]*\| [^\n]*peak memory ([0-9.]+) MiB)");
    std::vector<double> out;
    for (auto it = std::sregex_iterator(log.begin(), log.end(), peak); it != std::sregex_iterator(); ++it)
      out.push_back(std::stod((*it)[1]));
    return out;
  };
  const std::string budget = "--env TESSERA_CACHE_MB=" + std::to_string(kBudgetMiB);
  const auto still = dir.runFarm(scene("still.yaml", "{play: false}"), 2, 1, kFrames, 120, budget);
  ASSERT_EQ(still.exit_code, 0) << still.output;
  const auto one_step = peaks(still.output);
  // Two loops over the 12 steps: the budget holds one renderer window (128 x 128 x 57..73
  // voxels, 6.5..8.4 MiB with the caster's copy) besides the shown step, so the second loop
  // reads every step again, once.
  const auto r = dir.runFarm(scene("play.yaml", "{play: true}"), 2, 1, kFrames, 120, budget);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m = metrics(dir);
  ASSERT_EQ(m.size(), (size_t)kFrames);
  uint64_t read = 0;
  for (const auto& f : m) read += f["render_bytes_read"].get<uint64_t>();
  // Two renderers' windows: the volume once plus the ghost slices they share (2 x 128 x 128).
  const uint64_t step_bytes = 4ull * kSize * kSize * kSize, share_and_ghost = step_bytes + 4ull * 2 * kSize * kSize;
  EXPECT_LE(read, (uint64_t)(1.1 * kFrames * share_and_ghost)) << "read per frame: " << read / kFrames;
  EXPECT_GE(read, (kFrames - 1) * step_bytes) << "every frame's step was read";
  // The cache's own count: within the budget besides the shown step, every renderer.
  const std::regex held("step cache: budget " + std::to_string(kBudgetMiB) + R"( MiB, held at most ([0-9.]+) MiB)");
  int caches = 0;
  for (auto it = std::sregex_iterator(r.output.begin(), r.output.end(), held); it != std::sregex_iterator(); ++it, ++caches)
    EXPECT_LE(std::stod((*it)[1]), kBudgetMiB) << (*it)[0];
  EXPECT_EQ(caches, 2) << r.output;
  // And the process: playing holds at most the budget and one brick set on its way in more
  // than showing one step (all 12 steps would be 12 x 8 MiB more); 4 MiB of allocator slack.
  const auto playing = peaks(r.output);
  ASSERT_EQ(playing.size(), 2u) << r.output;
  ASSERT_EQ(one_step.size(), 2u) << still.output;
  // A renderer's held step: floats and the caster's bricked uint16 copy (about 6.9 bytes a
  // voxel), for a window of at most 80 of the 128 slices.
  const double window_mib = (4.0 * kSize * kSize * 80 + 2.0 * 729 * 16 * 16 * 10) / (1 << 20);
  for (int i = 0; i < 2; ++i)
    EXPECT_LE(playing[i], *std::max_element(one_step.begin(), one_step.end()) + kBudgetMiB + window_mib + 4)
        << "renderer peaks still " << one_step[0] << ", " << one_step[1] << " MiB";
}

}  // namespace
}  // namespace tessera::test
