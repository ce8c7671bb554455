// A jittered scene (`quality: {jitter: true}`) on the farm against tessera-render: the jitter
// travels in FrameParams' quality, and every renderer samples each pixel's ray on the same
// jittered grid, so the frames match the one-process render within the accuracy contract.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(JitterFarm, ThreeRenderersMatchTesseraRender) {
  FarmDir dir("jitter-farm");
  const int frames = 3;
  const fs::path scene = dir.path() / "skin.yaml", mid = dir.path() / "skin-mid-step.yaml";
  const std::string common = "volume: {generator: {name: head, size: 48}}\n"
                             "transfer_function: [[0, 0.9, 0.55, 0.45, 0], [0.22, 0.9, 0.55, 0.45, 0], "
                             "[0.27, 0.9, 0.55, 0.45, 1], [0.32, 0.9, 0.55, 0.45, 0], [1, 0.9, 0.55, 0.45, 0]]\n"
                             "camera: {eye: [1.2, 0.5, 1.9], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                             "shading: true\nimage: [64, 48]\norbit: {frames: " +
                             std::to_string(frames) + ", degrees: 120}\n";
  std::ofstream(scene) << common << "quality: {jitter: true}\n";
  std::ofstream(mid) << common;
  expectFarmMatchesRender(dir, scene, frames, 3, 1, "direct-send", 600, "jitter");
  // The jitter shows at this size: a farm that lost it would not pass (frame 0 differs from
  // the mid-step render by 21 levels).
  EXPECT_FALSE(dir.matches(dir.farmFrame(0), dir.reference(mid, 0), 1, "jitter_vs_mid_step"));
}

}  // namespace
}  // namespace tessera::test
