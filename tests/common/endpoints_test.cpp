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

// A renderer's swap socket: a port the system picks, advertised as a peer can reach it.
TEST(Endpoints, SwapSocketOnAPortTheSystemPicks) {
  const Endpoints tcp = makeEndpoints("tcp://127.0.0.1:5550");
  unsetenv("TESSERA_BIND_HOST");
  EXPECT_EQ(tcp.swapBind("ab12"), "tcp://127.0.0.1:*");
  EXPECT_EQ(tcp.swapAdvertised("tcp://127.0.0.1:41234", ""), "tcp://127.0.0.1:41234");
  EXPECT_EQ(tcp.swapAdvertised("tcp://0.0.0.0:41234", "node7"), "tcp://node7:41234");
  // Bound on every interface, nothing advertised: the address on the route to the master.
  EXPECT_EQ(tcp.swapAdvertised("tcp://0.0.0.0:41234", ""), "tcp://127.0.0.1:41234");
  setenv("TESSERA_BIND_HOST", "0.0.0.0", 1);
  EXPECT_EQ(tcp.swapBind("ab12"), "tcp://0.0.0.0:*");
  unsetenv("TESSERA_BIND_HOST");
  const Endpoints ipc = makeEndpoints("ipc://" + std::string(testing::TempDir()) + "swap-ep");
  EXPECT_EQ(ipc.swapBind("ab12"), ipc.base + "/renderer-ab12");
  EXPECT_EQ(ipc.swapAdvertised(ipc.base + "/renderer-ab12", "node7"), ipc.base + "/renderer-ab12");
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

// ZeroMQ binds addresses and interface names only: a host name (Slurm's NodeAddr is the
// node's name unless set) failed with a bare "No such device" (found by review).
TEST(Endpoints, AHostNameIsResolvedBeforeItIsBound) {
  EXPECT_EQ(bindableEndpoint("tcp://localhost:5550"), "tcp://127.0.0.1:5550");
  EXPECT_EQ(bindableEndpoint("tcp://localhost:*"), "tcp://127.0.0.1:*");
  for (const char* kept : {"tcp://10.1.2.3:5550", "tcp://0.0.0.0:*", "tcp://*:5550", "tcp://lo:5550", "tcp://[::1]:5550",
                           "ipc:///tmp/x/master-pub", "inproc://farm"})
    EXPECT_EQ(bindableEndpoint(kept), kept);
  try {
    bindableEndpoint("tcp://no-such-host.invalid:5550");
    ADD_FAILURE() << "an unknown host was bound";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind tcp://no-such-host.invalid:5550"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("TESSERA_BIND_HOST"), std::string::npos) << e.what();
  }
}

// A stage checks that the address it has peers send to is its own (a display or compositor
// on a host of its own without TESSERA_DISPLAY_HOST / ADVERTISE_HOST got nothing).
TEST(Endpoints, AnEndpointIsHereWhenItsHostIsAnAddressOfThisMachine) {
  for (const char* here : {"tcp://127.0.0.1:5552", "tcp://localhost:5552", "tcp://0.0.0.0:5552", "tcp://[::1]:5552",
                           "ipc:///tmp/x/display", "tcp://no-such-host.invalid:5552"})
    EXPECT_TRUE(endpointIsHere(here)) << here;
  EXPECT_TRUE(endpointIsHere("tcp://" + makeEndpoints("tcp://127.0.0.1:5550").localAddressTowardMaster() + ":1"));
  EXPECT_TRUE(endpointIsHere("tcp://127.0.1.1:5552")) << "Debian's address for the host's own name";
  for (const char* away : {"tcp://192.0.2.1:5552", "tcp://198.51.100.7:5552"})  // documentation addresses
    EXPECT_FALSE(endpointIsHere(away)) << away;
}

}  // namespace
}  // namespace tessera
