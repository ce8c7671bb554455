// Endpoint naming: one base address gives every stage's socket, hosts from the environment.
#include "common/net/endpoints.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace tessera {
namespace {

TEST(Endpoints, TcpPortsFollowTheBase) {
  const Endpoints ep = makeEndpoints("tcp://10.1.2.3:5550");
  EXPECT_EQ(ep.masterPub(), "tcp://10.1.2.3:5550");
  EXPECT_EQ(ep.masterControl(), "tcp://10.1.2.3:5551");
  EXPECT_EQ(ep.compositorOn(1, "10.1.2.9"), "tcp://10.1.2.9:5561");
}

TEST(Endpoints, DisplayHostFromTheEnvironmentAndEmptyMeansUnset) {
  const Endpoints ep = makeEndpoints("tcp://master:5550");
  setenv("TESSERA_DISPLAY_HOST", "", 1);  // compose.yaml passes unset settings as empty
  EXPECT_EQ(ep.display(), "tcp://master:5552");
  setenv("TESSERA_DISPLAY_HOST", "viz", 1);
  EXPECT_EQ(ep.display(), "tcp://viz:5552");
  unsetenv("TESSERA_DISPLAY_HOST");
}

// 'ip' advertising: the local address on the route to the master (loopback here).
TEST(Endpoints, LocalAddressTowardTheMaster) {
  EXPECT_EQ(makeEndpoints("tcp://127.0.0.1:5550").localAddressTowardMaster(), "127.0.0.1");
  EXPECT_THROW(makeEndpoints("inproc://x").localAddressTowardMaster(), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
