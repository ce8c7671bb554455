// Never silent: a stage started without its master says, within seconds, what it waits for
// and where, instead of waiting without a word until it is killed.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(StageWaits, ALoneRendererSaysWhichMasterItWaitsFor) {
  FarmDir dir("waits");
  const std::string base = "ipc://" + (dir.path() / "sockets").string();
  // timeout stops it after 4 s: the notice is due after 2 s.
  const auto r = runCommand("env TESSERA_ENDPOINTS=" + base + " " + bin("tessera-renderer"), 4);
  EXPECT_NE(r.output.find("renderer waiting 2 s for the master at " + base + "/master-pub"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("TESSERA_ENDPOINTS=" + base), std::string::npos) << r.output;
}

// A new-user finding: a lone master said nothing about the stages it waits for.
TEST(StageWaits, ALoneMasterSaysWhichStagesItWaitsForAndWhere) {
  FarmDir dir("master-waits");
  const std::string base = "ipc://" + (dir.path() / "sockets").string();
  const auto r = runCommand("env TESSERA_ENDPOINTS=" + base + " " + bin("tessera-master") + " --renderers 2", 4);
  EXPECT_NE(r.output.find("waiting for stages at " + base + "/master-ctl: renderers 0/2 compositors 0/1 display 0/1"),
            std::string::npos)
      << r.output;
}

// A master whose volume file turns out bad while it reads it (a NaN in the last voxel of a
// 1 GiB file, sparse on disk) says so to the stages waiting for their Welcome: they end with
// its reason within seconds, not after their 120 s wait.
TEST(StageWaits, AWaitingRendererHearsWhyTheMastersVolumeCouldNotBeRead) {
  FarmDir dir("bad-volume");
  const std::string base = "ipc://" + (dir.path() / "sockets").string();
  const fs::path raw = dir.path() / "nan.raw";
  {
    const size_t bytes = size_t(512) * 512 * 1024 * 4;
    std::ofstream out(raw, std::ios::binary);
    out.seekp((std::streamoff)(bytes - 4));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    out.write(reinterpret_cast<const char*>(&nan), 4);
  }
  const fs::path scene = dir.path() / "nan.yaml";
  std::ofstream(scene) << "volume: {file: nan.raw, dims: [512, 512, 1024], type: float32}\n";
  const std::string env = "env TESSERA_ENDPOINTS=" + base + " TESSERA_SCENE=" + scene.string() + " ";
  const auto t0 = std::chrono::steady_clock::now();
  // The renderer first, so it hears the master's probes while the master reads.
  const std::string log = (dir.path() / "renderer.log").string();
  const auto r = runCommand("sh -c '(" + env + bin("tessera-renderer") + " > " + log + " 2>&1; echo renderer exit $? >> " +
                                log + ") & sleep 1; " + env + bin("tessera-master") + " --renderers 1; wait'",
                            60);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream in(dir.path() / "renderer.log");
  const std::string renderer((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(r.output.find("non-finite value"), std::string::npos) << r.output;
  EXPECT_NE(renderer.find("shut down before this renderer joined: the volume could not be read: "), std::string::npos)
      << renderer << "\n" << r.output;
  EXPECT_NE(renderer.find("nan.yaml: volume: "), std::string::npos) << "the scene is named\n" << renderer;
  EXPECT_NE(renderer.find("at voxel (511, 511, 1023)"), std::string::npos) << renderer;
  EXPECT_NE(renderer.find("renderer exit 0"), std::string::npos) << "the run ended: no failure of the renderer\n" << renderer;
  EXPECT_LT(s, 30) << "the renderer waited for its Welcome";
}

}  // namespace
}  // namespace tessera::test
