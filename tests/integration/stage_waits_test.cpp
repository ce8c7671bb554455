// Never silent: a stage started without its master says, within seconds, what it waits for
// and where, instead of waiting without a word until it is killed.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace tessera::test
