// CURVE across hosts, tried on loopback with TESSERA_CURVE=on: the farm's processes share the
// keys created in TESSERA_KEYS on first start and render the contract's frames; a peer with
// another key, or without CURVE, is refused by the master and the refusal is logged.
#include <gtest/gtest.h>

#include <cstdlib>
#include <future>
#include <random>
#include <thread>

#include <zmq.hpp>

#include "common/net/curve.h"
#include "common/wire/protocol.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

TEST(FarmCurve, MembersShareTheKeyAndStrangersAreRefused) {
  FarmDir dir("curve");
  const int frames = 30;
  auto scene = dir.writeScene(frames);
  std::random_device rd;
  const int base = 20000 + (int)(rd() % 20000);
  const std::string keys = (dir.path() / "keys").string();
  setenv("TESSERA_CURVE", "on", 1);  // children of tessera-up inherit it
  setenv("TESSERA_KEYS", keys.c_str(), 1);
  auto farm = std::async(std::launch::async, [&] {
    return dir.runFarm(scene, 2, 1, frames, 120, "", "tcp://127.0.0.1:" + std::to_string(base));
  });
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!fs::exists(dir.frame(1)) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(20ms);
  unsetenv("TESSERA_CURVE");
  unsetenv("TESSERA_KEYS");
  ASSERT_TRUE(fs::exists(dir.frame(1))) << "the farm produced no frame";

  // A stranger with its own keys who knows the farm's public key, and one without CURVE.
  zmq::context_t ctx;
  const std::string control = "tcp://127.0.0.1:" + std::to_string(base + 1);
  const FarmKeys farm_keys = readFarmKeys(keys), other = generateFarmKeys();
  zmq::socket_t stranger(ctx, zmq::socket_type::dealer), plain(ctx, zmq::socket_type::dealer);
  for (auto* s : {&stranger, &plain}) s->set(zmq::sockopt::linger, 0);
  stranger.set(zmq::sockopt::curve_serverkey, farm_keys.public_z85);
  stranger.set(zmq::sockopt::curve_publickey, other.public_z85);
  stranger.set(zmq::sockopt::curve_secretkey, other.secret_z85);
  stranger.connect(control);
  plain.connect(control);
  auto forged = proto::encode(proto::FrameDone{2, 0, 0, 0, 0, 0}, 0);
  for (auto* s : {&stranger, &plain}) (void)s->send(zmq::buffer(forged.data(), forged.size()), zmq::send_flags::dontwait);

  auto run = farm.get();
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("CURVE on"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("not the farm key"), std::string::npos) << "the stranger was not refused\n" << run.output;
  EXPECT_TRUE(fs::exists(fs::path(keys) / "farm.key")) << "keys were not created on first start";
  // 1/255: the sort-last contract, unchanged by encryption.
  for (int k : {0, frames - 1}) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
}

}  // namespace
}  // namespace tessera::test
