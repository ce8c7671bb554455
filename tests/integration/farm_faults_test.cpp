// A running farm under bad input and failures: garbage, truncated and out-of-date
// messages are dropped and counted while the frames stay correct; a killed stage is
// named and the launcher stops the farm cleanly, leaving no process behind.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <fstream>
#include <future>
#include <thread>

#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "common/wire/protocol.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

// Pids of farm processes whose environment names this test's socket folder.
std::vector<int> farmPids(const fs::path& sockets, const std::string& program = "") {
  std::vector<int> pids;
  for (const auto& e : fs::directory_iterator("/proc")) {
    int pid = std::atoi(e.path().filename().c_str());
    if (pid <= 0) continue;
    std::ifstream env(e.path() / "environ"), cmd(e.path() / "cmdline");
    std::string envs((std::istreambuf_iterator<char>(env)), {}), cmdline((std::istreambuf_iterator<char>(cmd)), {});
    if (envs.find(sockets.string()) == std::string::npos) continue;
    if (cmdline.find("tessera-") == std::string::npos || cmdline.find("tessera-up") != std::string::npos) continue;
    if (program.empty() || cmdline.find(program) != std::string::npos) pids.push_back(pid);
  }
  return pids;
}

bool waitFor(const std::function<bool()>& cond, std::chrono::milliseconds limit) {
  auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (cond()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return cond();
}

std::vector<std::byte> bytesOf(const std::string& s) {
  std::vector<std::byte> b(s.size());
  std::memcpy(b.data(), s.data(), s.size());
  return b;
}

void push(zmq::context_t& ctx, const std::string& endpoint, zmq::socket_type type,
          const std::vector<std::vector<std::byte>>& messages) {
  zmq::socket_t s(ctx, type);
  s.set(zmq::sockopt::linger, 2000);
  s.connect(endpoint);
  for (const auto& m : messages) s.send(zmq::buffer(m.data(), m.size()), zmq::send_flags::none);
}

TEST(FarmFaults, BadMessagesAreDroppedCountedAndFramesStayCorrect) {
  FarmDir dir("garbage");
  const int frames = 24;
  auto scene = dir.writeScene(frames, 40, 160, 120);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, frames, 180, "--env TESSERA_WINDOW=off"); });
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir.frame(1)); }, 60s)) << "the farm produced no frame";

  // Garbage, a truncated header, an out-of-date protocol version and a piece whose
  // checksum does not match, sent to every endpoint that accepts peer messages.
  auto valid = proto::encode(proto::Heartbeat{proto::Role::Renderer, 0}, 0);
  auto old_version = valid;
  old_version[4] = std::byte{0};
  old_version[5] = std::byte{0};
  auto truncated = std::vector<std::byte>(valid.begin(), valid.begin() + 10);
  proto::Piece piece;
  piece.frame = 1000000;
  piece.region = {0, 0, 8, 8};
  piece.active = {0, 0, 2, 2};
  piece.pixels.assign(16, std::byte{7});
  auto bad_piece = proto::encode(piece, 0, Codec::Lzo);
  bad_piece.back() ^= std::byte{0x5A};
  std::vector<std::vector<std::byte>> junk = {bytesOf("garbage, not a message"), truncated, old_version, bad_piece,
                                              std::vector<std::byte>(5000, std::byte{0xFF})};
  zmq::context_t ctx;
  push(ctx, "ipc://" + (sockets / "compositor-0").string(), zmq::socket_type::push, junk);
  push(ctx, "ipc://" + (sockets / "display").string(), zmq::socket_type::push, junk);
  push(ctx, "ipc://" + (sockets / "master-ctl").string(), zmq::socket_type::dealer, junk);

  auto run = farm.get();
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k : {0, frames - 1}) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k;
    // 1/255: pieces are quantized to rgba8 once before compositing.
    EXPECT_LE(maxAbsDiff(readPng(dir.frame(k).string()), dir.reference(scene, k)), 1) << "frame " << k;
  }
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  double master = 0, composite = 0, display = 0;
  int lines = 0;
  for (std::string line; std::getline(metrics, line); ++lines) {
    auto j = nlohmann::json::parse(line);
    master = std::max(master, j["master_dropped"].get<double>());
    composite = std::max(composite, j["composite_dropped"].get<double>());
    display = std::max(display, j["display_dropped"].get<double>());
  }
  EXPECT_EQ(lines, frames);
  EXPECT_GE(master, (double)junk.size()) << "master did not count the bad messages";
  EXPECT_GE(composite, (double)junk.size()) << "compositor did not count the bad messages";
  EXPECT_GE(display, (double)junk.size()) << "display did not count the bad messages";
  EXPECT_NE(run.output.find("dropped message"), std::string::npos) << "drops were not logged";
}

TEST(FarmFaults, KilledStageIsNamedAndFarmStopsCleanly) {
  FarmDir dir("kill");
  auto scene = dir.writeScene(1000, 40, 200, 200);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, 1000, 120); });
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir.frame(1)); }, 60s)) << "the farm produced no frame";
  auto victims = farmPids(sockets, "tessera-renderer");
  ASSERT_EQ(victims.size(), 2u);
  ASSERT_EQ(kill(victims[0], SIGKILL), 0);
  ASSERT_EQ(farm.wait_for(60s), std::future_status::ready) << "the launcher did not stop the farm";
  auto run = farm.get();
  EXPECT_NE(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("renderer"), std::string::npos);
  EXPECT_NE(run.output.find("died"), std::string::npos) << run.output;
  EXPECT_TRUE(waitFor([&] { return farmPids(sockets).empty(); }, 10s)) << "farm processes left behind";
}

}  // namespace
}  // namespace tessera::test
