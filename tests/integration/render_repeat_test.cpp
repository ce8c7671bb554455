// tessera-render --repeat renders each time into the memory of the image before, as a
// renderer's frames do (fresh pages were ~6% of a measured frame): the image it writes must be
// the image of a single render, bit for bit, whole and in bricks (where a brick's image is
// reused for the next brick and the composite for the next render).
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(RenderRepeat, RepeatedRendersWriteTheImageOfOne) {
  FarmDir dir("repeat");
  const std::string scene = (dir.path() / "scene.yaml").string();
  std::ofstream(scene) << "volume:\n  generator: {name: hollow-shell, size: 48, seed: 1}\n"
                       << "camera: {eye: [0.3, 0.5, 2.2], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                       << "image: [160, 120]\nquality: default\n";
  auto floats = [&](int bricks, int repeat) {
    const std::string n = std::to_string(bricks), times = std::to_string(repeat);
    std::string raw = (dir.path() / "r").string();
    raw += n;
    raw += "-";
    raw += times;
    raw += ".f32";
    std::string cmd = bin("tessera-render");
    cmd += " " + scene + " --bricks " + n + " --repeat " + times + " -o " + dir.path().string() + "/x.png --raw " + raw;
    const auto r = runCommand(cmd, 120);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(raw, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (int bricks : {1, 3}) {
    const std::string once = floats(bricks, 1);
    ASSERT_GT(once.size(), 160u * 120 * 16 - 1) << "no float image";
    EXPECT_TRUE(floats(bricks, 3) == once) << bricks << " brick(s): three renders differ from one";
  }
}

// --stats --repeat N prints the best render's time and the mean of the renders after the first
// (what the goals' efficiency compares a farm's frames a second with): never below the best.
TEST(RenderRepeat, StatsGiveTheBestAndTheMeanAfterTheFirst) {
  FarmDir dir("repeat-stats");
  auto stats = [&](int repeat) {
    const auto r = runCommand(bin("tessera-render") + " --image 96x64 --stats --repeat " + std::to_string(repeat) + " -o " +
                                  dir.path().string() + "/x.png",
                              120);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output;
  };
  const std::regex best_re("time_ms=([0-9.]+)"), mean_re("mean_ms=([0-9.]+)");
  std::smatch best, mean;
  const std::string once = stats(1);
  ASSERT_TRUE(std::regex_search(once, best, best_re)) << once;
  EXPECT_FALSE(std::regex_search(once, mean, mean_re)) << "one render has no mean after the first: " << once;
  const std::string four = stats(4);
  ASSERT_TRUE(std::regex_search(four, best, best_re)) << four;
  ASSERT_TRUE(std::regex_search(four, mean, mean_re)) << four;
  EXPECT_GT(std::stod(best[1]), 0) << four;
  EXPECT_GE(std::stod(mean[1]), std::stod(best[1])) << four;
}

}  // namespace
}  // namespace tessera::test
