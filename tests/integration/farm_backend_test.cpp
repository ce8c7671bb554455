// The farm on the second volume backend (renderers with --backend osmesa, GLSL on llvmpipe)
// matches tessera-render on that backend: the backend interface carries the same contract.
#include <gtest/gtest.h>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(FarmBackends, OsmesaRenderersMatchOneProcessOsmesa) {
  FarmDir dir("backend-osmesa");
  const int frames = 2;
  auto scene = dir.writeScene(6);
  auto run = dir.runFarm(scene, 2, 1, frames, 180, "--env TESSERA_BACKEND=osmesa");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("joined backend=osmesa"), std::string::npos) << "renderers did not use osmesa\n" << run.output;
  for (int k = 0; k < frames; ++k) {
    fs::path ref = dir.path() / ("ref_osmesa_" + std::to_string(k) + ".png");
    auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --backend osmesa --frame " + std::to_string(k) +
                            " -o " + ref.string(),
                        120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    Image8 farm = readPng(dir.frame(k).string());
    // 1/255: each brick's piece is rounded once before compositing (as on the cpu backend).
    EXPECT_LE(maxAbsDiff(farm, readPng(ref.string())), 1) << "frame " << k << " in " << dir.path();
    EXPECT_GT(activeRegion(farm).area(), 100) << "frame " << k << " is (nearly) empty";
  }
}

}  // namespace
}  // namespace tessera::test
