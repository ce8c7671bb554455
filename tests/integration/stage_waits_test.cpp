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

}  // namespace
}  // namespace tessera::test
