// CURVE between farm processes: the farm key admits, any other key is refused and counted,
// keys on disk are checked, and only endpoints that leave the host need it.
#include "common/net/curve.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <unistd.h>

#include "common/net/transport.h"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// A free loopback port: bind to port 0 and read back what the kernel chose.
std::string loopbackEndpoint(zmq::socket_t& s) {
  s.bind("tcp://127.0.0.1:*");
  return s.get(zmq::sockopt::last_endpoint);
}

bool receiveWithin(zmq::socket_t& s, std::chrono::milliseconds limit, std::string& got) {
  zmq::pollitem_t items[] = {{s.handle(), 0, ZMQ_POLLIN, 0}};
  for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
    pollFor(items, 1, 50ms);
    if (!(items[0].revents & ZMQ_POLLIN)) continue;
    zmq::message_t m;
    (void)s.recv(m);
    got = m.to_string();
    return true;
  }
  return false;
}

TEST(Curve, FarmKeyIsAdmittedAndAnyOtherKeyRefusedAndCounted) {
  zmq::context_t ctx;
  const FarmKeys farm = generateFarmKeys();
  CurveAuth auth(ctx, farm);
  zmq::socket_t server(ctx, zmq::socket_type::pull);
  server.set(zmq::sockopt::linger, 0);
  auth.makeServer(server);
  const std::string endpoint = loopbackEndpoint(server);

  // A stranger that knows the farm's public key but not its secret key.
  zmq::socket_t stranger(ctx, zmq::socket_type::push);
  stranger.set(zmq::sockopt::linger, 0);
  const FarmKeys other = generateFarmKeys();
  stranger.set(zmq::sockopt::curve_serverkey, farm.public_z85);
  stranger.set(zmq::sockopt::curve_publickey, other.public_z85);
  stranger.set(zmq::sockopt::curve_secretkey, other.secret_z85);
  stranger.connect(endpoint);
  (void)stranger.send(zmq::str_buffer("forged"), zmq::send_flags::dontwait);
  for (int i = 0; i < 100 && auth.refused() == 0; ++i) std::this_thread::sleep_for(20ms);  // bounded: 2 s
  EXPECT_GE(auth.refused(), 1u) << "the stranger's handshake was not refused";
  std::string got;
  EXPECT_FALSE(receiveWithin(server, 200ms, got)) << "a message from a stranger arrived: " << got;

  zmq::socket_t member(ctx, zmq::socket_type::push);
  member.set(zmq::sockopt::linger, 0);
  auth.makeClient(member);
  member.connect(endpoint);
  (void)member.send(zmq::str_buffer("frame"), zmq::send_flags::none);
  ASSERT_TRUE(receiveWithin(server, 5000ms, got)) << "the member's message did not arrive";
  EXPECT_EQ(got, "frame");
}

TEST(Curve, KeysRoundTripThroughTheirFolderAndBadFilesAreNamed) {
  const fs::path dir = fs::temp_directory_path() / ("tessera-curve-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const FarmKeys made = loadOrCreateFarmKeys(dir.string());
  const FarmKeys again = loadOrCreateFarmKeys(dir.string());
  EXPECT_EQ(made.secret_z85, again.secret_z85) << "a second start must reuse the folder's keys";
  EXPECT_EQ(fs::status(dir / "farm.key").permissions() & fs::perms::others_read, fs::perms::none);

  EXPECT_FALSE(writeFarmKeys(dir.string(), generateFarmKeys())) << "an existing farm.key was replaced";
  EXPECT_EQ(readFarmKeys(dir.string()).secret_z85, made.secret_z85);
  std::ofstream(dir / "farm.pub") << generateFarmKeys().public_z85 << "\n";
  try {
    readFarmKeys(dir.string());
    FAIL() << "a public key from another farm was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("does not belong"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "farm.key") << "short\n";
  try {
    readFarmKeys(dir.string());
    FAIL() << "a truncated key was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("farm.key"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// Processes of a farm start together: one creates the keys while the others read them as soon
// as farm.key exists. No reader may see a farm.pub that is there but not yet written.
TEST(Curve, KeysBeingCreatedAreNeverReadHalfWritten) {
  const fs::path root = fs::temp_directory_path() / ("tessera-curve-race-" + std::to_string(::getpid()));
  for (int round = 0; round < 200; ++round) {
    const fs::path dir = root / std::to_string(round);
    std::atomic<bool> done{false};
    std::string failure;
    std::thread reader([&] {
      while (!done && failure.empty()) {
        if (!fs::exists(dir / "farm.key")) continue;
        try {
          (void)readFarmKeys(dir.string());
        } catch (const std::exception& e) {
          failure = e.what();
        }
      }
    });
    (void)loadOrCreateFarmKeys(dir.string());
    done = true;
    reader.join();
    ASSERT_EQ(failure, "") << "round " << round;
  }
  fs::remove_all(root);
}

// ZeroMQ's "Address already in use" named neither the address nor what to change (found by
// review: two farms on one port block).
TEST(Curve, ABindThatFailsNamesItsEndpoint) {
  zmq::context_t ctx;
  zmq::socket_t first(ctx, zmq::socket_type::pull), second(ctx, zmq::socket_type::pull);
  first.set(zmq::sockopt::linger, 0), second.set(zmq::sockopt::linger, 0);
  const std::string taken = loopbackEndpoint(first);
  try {
    bindTo(second, taken);
    ADD_FAILURE() << "bound a taken port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind " + taken + ": "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the port is taken"), std::string::npos) << e.what();
  }
  const std::string named = "tcp://localhost:" + taken.substr(taken.rfind(':') + 1);
  try {
    bindTo(second, named);
    ADD_FAILURE() << "bound a taken port by name";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind " + named + " (" + taken + ")"), std::string::npos) << e.what();
  }
}

// A client whose server holds another farm key, or has no CURVE, only sees its handshakes
// fail; it waited out the join timeout asking whether the master runs (found by review).
TEST(Curve, AClientTellsAnotherFarmKeyAndAMissingMechanismFromItsHandshakes) {
  zmq::context_t ctx;
  const FarmKeys farm = generateFarmKeys();
  CurveAuth auth(ctx, farm);  // one per context: a second would bind the same ZAP endpoint
  const FarmKeys another = generateFarmKeys();
  zmq::socket_t server(ctx, zmq::socket_type::pub), plain(ctx, zmq::socket_type::pub);
  server.set(zmq::sockopt::linger, 0), plain.set(zmq::sockopt::linger, 0);
  auth.makeServer(server);
  const std::string curve_at = loopbackEndpoint(server), plain_at = loopbackEndpoint(plain);
  auto watch = [&](const FarmKeys* as, const std::string& at) {
    zmq::socket_t client(ctx, zmq::socket_type::sub);
    client.set(zmq::sockopt::linger, 0);
    if (as) {  // as CurveAuth::makeClient does with these keys
      client.set(zmq::sockopt::curve_serverkey, as->public_z85);
      client.set(zmq::sockopt::curve_publickey, as->public_z85);
      client.set(zmq::sockopt::curve_secretkey, as->secret_z85);
    }
    HandshakeWatch w(ctx, client);
    client.connect(at);
    std::string why;
    for (int i = 0; i < 150 && why.empty(); ++i) {  // bounded: 3 s
      std::this_thread::sleep_for(20ms);
      why = w.failing(5);
    }
    return why;
  };
  const std::string stranger = watch(&another, curve_at);
  EXPECT_NE(stranger.find("farm key is not the master's"), std::string::npos) << stranger;
  // Which end tells the mismatch first is a race: the client sees the mismatch, or closes.
  auto either = [](const std::string& why, const char* a, const char* b) {
    return why.find(a) != std::string::npos || why.find(b) != std::string::npos;
  };
  const std::string no_curve = watch(nullptr, curve_at);
  EXPECT_TRUE(either(no_curve, "CURVE is on at one end only (TESSERA_CURVE here off",
                     "CURVE is off here, and the master probably has it on")) << no_curve;
  const std::string only_here = watch(&farm, plain_at);
  EXPECT_TRUE(either(only_here, "CURVE is on at one end only (TESSERA_CURVE here on", "or CURVE is off at the master"))
      << only_here;
  EXPECT_EQ(watch(&farm, curve_at), "") << "the farm's own key failed its handshakes";
}

// A stage never makes a farm key of its own (no peer would admit it): it waits for the
// master's, then names the folder.
TEST(Curve, AStageWaitsForTheMastersKeyAndNamesTheFolderWhenItNeverComes) {
  const fs::path dir = fs::temp_directory_path() / ("tessera-await-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  try {
    (void)awaitFarmKeys(dir.string(), 0.3);
    ADD_FAILURE() << "keys from nowhere";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no farm key in " + (dir / "farm.key").string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "farm.key")) << "the stage made a key of its own";
  std::thread master([&] {
    std::this_thread::sleep_for(200ms);
    (void)loadOrCreateFarmKeys(dir.string());
  });
  const FarmKeys got = awaitFarmKeys(dir.string(), 10);
  master.join();
  EXPECT_EQ(got.public_z85, readFarmKeys(dir.string()).public_z85);
  fs::remove_all(dir);
}

TEST(Curve, OnlyEndpointsThatLeaveTheHostNeedIt) {
  EXPECT_FALSE(endpointLeavesHost("ipc:///tmp/farm/master-pub"));
  EXPECT_FALSE(endpointLeavesHost("inproc://farm-display"));
  EXPECT_FALSE(endpointLeavesHost("tcp://127.0.0.1:5550"));
  EXPECT_FALSE(endpointLeavesHost("tcp://localhost:5550"));
  EXPECT_FALSE(endpointLeavesHost("tcp://[::1]:5550"));
  EXPECT_TRUE(endpointLeavesHost("tcp://10.0.0.2:5550"));
  EXPECT_TRUE(endpointLeavesHost("tcp://master:5550"));
  EXPECT_TRUE(endpointLeavesHost("tcp://0.0.0.0:5550"));
}

}  // namespace
}  // namespace tessera
