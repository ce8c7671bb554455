// The farm's maximum and minimum intensity projections (scene `blend: maximum`, `minimum`)
// against tessera-render's: pieces carry each ray's largest value (or its smallest's
// complement), merged by maxima in the compositors or in the renderers' binary swap, and
// mapped once, so the frames match the one-process render within the accuracy contract.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

// The Marschner-Lobb volume as a projection (`blend`, `tf` its transfer function's points,
// `more` further scene keys).
fs::path writeProjectionScene(const FarmDir& dir, int frames, const std::string& blend, const std::string& tf,
                              const std::string& more = "") {
  const fs::path scene = dir.path() / (blend + ".yaml");
  std::ofstream(scene) << "volume: {generator: {name: marschner-lobb, size: 48}}\ntransfer_function: " << tf
                       << "\nblend: " << blend << "\nimage: [64, 48]\norbit: {frames: " << frames << ", degrees: 90}\n"
                       << more;
  return scene;
}

// A colour map steep where most rays' largest values of the Marschner-Lobb volume lie (0.8 to
// 0.9, opacity 0 to 1): a value rounded as rgba16f pieces would round it (by up to 1/2048)
// moves the colour by more than a level, so only exact values match.
fs::path writeMipScene(const FarmDir& dir, int frames) {
  return writeProjectionScene(dir, frames, "maximum",
                              "[[0, 0, 0, 0, 0], [0.8, 0.1, 0.2, 0.9, 0], [0.9, 1, 0.6, 0.1, 1], [1, 1, 1, 0.8, 1]]");
}

// A 3-frame orbit on `renderers` + `compositors` with `compositing`, frame by frame, within the
// contract's 1/255. Merging by maxima is exact and the values travel as rgba32f (these frames
// come out equal to the bit); as rgba16f pieces they differed by 2 levels.
void runAndCompare(const char* name, int renderers, int compositors, const char* compositing) {
  FarmDir dir(name);
  const int frames = 3;
  expectFarmMatchesRender(dir, writeMipScene(dir, frames), frames, renderers, compositors, compositing, 400, "mip");
}

TEST(MaxIntensityFarm, CompositorsMergeMaximaAsTesseraRenderDoes) { runAndCompare("mip-direct", 4, 2, "direct-send"); }

TEST(MaxIntensityFarm, BinarySwapMergesMaximaAsTesseraRenderDoes) { runAndCompare("mip-swap", 3, 0, "binary-swap"); }

// The minimum projection travels as the maximum of the values' complements: the same merges,
// mapped by the mirrored colour map. Its map is steep where most rays' smallest values of the
// Marschner-Lobb volume lie (0.1 to 0.2) and clear above 0.5, so rays whose smallest value is
// larger show nothing and bricks without one below it are passed over. Cropped, as a minimum
// projection is seen (scenes/minip.yaml): the crop box cuts the bricks.
void runMinimumAndCompare(const char* name, int renderers, int compositors, const char* compositing) {
  FarmDir dir(name);
  const int frames = 3;
  const fs::path scene = writeProjectionScene(dir, frames, "minimum",
                                              "[[0, 1, 1, 0.8, 1], [0.1, 1, 0.6, 0.1, 1], [0.2, 0.1, 0.2, 0.9, 0.2],"
                                              " [0.5, 0, 0, 0, 0], [1, 0, 0, 0, 0]]",
                                              "crop: {x: [0.1, 0.8], z: [0.25, 0.75]}\n");
  expectFarmMatchesRender(dir, scene, frames, renderers, compositors, compositing, 400, "minip");
}

TEST(MaxIntensityFarm, CompositorsMergeMinimaAsTesseraRenderDoes) {
  runMinimumAndCompare("minip-direct", 4, 2, "direct-send");
}

TEST(MaxIntensityFarm, BinarySwapMergesMinimaAsTesseraRenderDoes) {
  runMinimumAndCompare("minip-swap", 3, 0, "binary-swap");
}

TEST(MaxIntensityFarm, TheOsmesaBackendRefusesItByName) {
  FarmDir dir("mip-osmesa");
  const fs::path scene = writeMipScene(dir, 1);
  const auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --backend osmesa -o " +
                                (dir.path() / "x.png").string(),
                            60);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("use backend cpu for `blend: maximum`"), std::string::npos) << r.output;
}

// A farm's renderer refuses at start, before it joins: no master is needed to hear why, and
// none would wait for a renderer that fails every frame.
TEST(MaxIntensityFarm, AnOsmesaRendererRefusesItAtStart) {
  FarmDir dir("mip-osmesa-stage");
  const fs::path scene = writeMipScene(dir, 1);
  const auto r = runCommand(bin("tessera-renderer") + " " + scene.string() + " --backend osmesa --endpoints ipc://" +
                                (dir.path() / "sockets").string(),
                            60);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("use backend cpu for `blend: maximum`"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("waiting"), std::string::npos) << "it waited for a master first:\n" << r.output;
}

}  // namespace
}  // namespace tessera::test
