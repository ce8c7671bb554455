// tessera-render --repeat renders each time into the memory of the image before, as a
// renderer's frames do (fresh pages were ~6% of a measured frame): the image it writes must be
// the image of a single render, bit for bit, whole and in bricks (where a brick's image is
// reused for the next brick and the composite for the next render).
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

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

}  // namespace
}  // namespace tessera::test
