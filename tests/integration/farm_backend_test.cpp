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
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    Image8 farm = dir.farmFrame(k);
    // 1/255: each brick's piece is rounded once before compositing (as on the cpu backend).
    EXPECT_TRUE(dir.matches(farm, dir.reference(scene, k, "--backend osmesa"), 1, "frame_" + std::to_string(k))) << "frame " << k;
    EXPECT_GT(activeRegion(farm).area(), 100) << "frame " << k << " is (nearly) empty";
  }
}

}  // namespace
}  // namespace tessera::test
