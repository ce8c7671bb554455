// The farm's crop (scene `crop`) against tessera-render's: each renderer cuts its bricks to the
// crop box, so the farm's frames match the one-process render within the accuracy contract,
// lit too (the gradients at the cut read the ghost voxels beyond it).
#include <gtest/gtest.h>

#include <fstream>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

void runAndCompare(const char* name, int renderers, int compositors, const char* compositing) {
  FarmDir dir(name);
  const int frames = 3;
  const fs::path scene = dir.path() / "crop.yaml";
  std::ofstream(scene) << "volume: {generator: {name: head, size: 48}}\n"
                          "crop: {x: [0.1, 0.55], y: [0.2, 1], z: [0, 0.7]}\n"
                          "camera: {eye: [0.9, 0.4, 1.1], target: [0, 0, 0], up: [0, 1, 0], fov: 40}\n"
                          "shading: true\nimage: [64, 48]\norbit: {frames: "
                       << frames << ", degrees: 120}\n";
  expectFarmMatchesRender(dir, scene, frames, renderers, compositors, compositing, 600, "crop");
}

TEST(CropFarm, DirectSendMatchesTesseraRender) { runAndCompare("crop-direct", 3, 1, "direct-send"); }

TEST(CropFarm, BinarySwapMatchesTesseraRender) { runAndCompare("crop-swap", 4, 0, "binary-swap"); }

}  // namespace
}  // namespace tessera::test
