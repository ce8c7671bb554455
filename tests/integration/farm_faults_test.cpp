// A running farm under bad input and failures: garbage, truncated and out-of-date
// messages are dropped and counted while the frames stay correct; a killed or frozen
// renderer or compositor is replaced (compose.yaml: restart: on-failure) or resumes and
// every frame is still done once and correctly; losing the master or the display stops
// the farm with a message that says so, leaving no process behind.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <numeric>
#include <thread>

#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "common/wire/protocol.h"
#include "common/wire/strips.h"
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

// swap: the renderers composite by binary swap, and their swap sockets get the junk too.
void expectBadMessagesDroppedAndCounted(bool swap) {
  FarmDir dir(swap ? "garbage-swap" : "garbage");
  const int frames = 24;
  auto scene = dir.writeScene(frames, 40, 160, 120);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] {
    return dir.runFarm(scene, 2, 1, frames, 180, swap ? "--env TESSERA_COMPOSITING=binary-swap" : "--env TESSERA_COMPOSITING=direct-send");
  });
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
  push(ctx, "ipc://" + (sockets / "compositor-0").string(), zmq::socket_type::dealer, junk);
  push(ctx, "ipc://" + (sockets / "display").string(), zmq::socket_type::dealer, junk);
  push(ctx, "ipc://" + (sockets / "master-ctl").string(), zmq::socket_type::dealer, junk);
  if (swap) {  // every renderer's swap socket (named by its identity, not its rank)
    int found = 0;
    for (const auto& e : fs::directory_iterator(sockets))
      if (e.path().filename().string().rfind("renderer-", 0) == 0)
        ++found, push(ctx, "ipc://" + e.path().string(), zmq::socket_type::dealer, junk);
    EXPECT_EQ(found, 2) << "swap sockets of the 2 renderers";
  }

  auto run = farm.get();
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k : {0, frames - 1}) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k;
    // 1/255: pieces are quantized to rgba8 once before compositing.
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
  }
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  double master = 0, composite = 0, display = 0, render = 0;
  int lines = 0;
  for (std::string line; std::getline(metrics, line); ++lines) {
    auto j = nlohmann::json::parse(line);
    render = std::max(render, j["render_dropped"].get<double>());
    master = std::max(master, j["master_dropped"].get<double>());
    composite = std::max(composite, j["composite_dropped"].get<double>());
    display = std::max(display, j["display_dropped"].get<double>());
  }
  EXPECT_EQ(lines, frames);
  EXPECT_GE(master, (double)junk.size()) << "master did not count the bad messages";
  EXPECT_GE(composite, (double)junk.size()) << "compositor did not count the bad messages";
  EXPECT_GE(display, (double)junk.size()) << "display did not count the bad messages";
  EXPECT_NE(run.output.find("dropped message"), std::string::npos) << "drops were not logged";
  if (swap) {
    EXPECT_NE(run.output.find("binary swap among 2 renderers"), std::string::npos) << run.output;
    EXPECT_GE(render, (double)junk.size()) << "the renderer did not count the bad messages";
  }
}

TEST(FarmFaults, BadMessagesAreDroppedCountedAndFramesStayCorrect) { expectBadMessagesDroppedAndCounted(false); }
TEST(FarmFaults, BadSwapMessagesAreDroppedCountedAndFramesStayCorrect) { expectBadMessagesDroppedAndCounted(true); }

// ---- losing a stage (issue 8): compose.yaml restarts renderers and compositors ------

constexpr int kFaultFrames = 150;

// Frame ids of out/metrics.jsonl in file order, and the last line.
struct MetricsLines {
  std::vector<int> frames;
  std::vector<nlohmann::json> lines;
};

MetricsLines readMetrics(const FarmDir& dir) {
  MetricsLines m;
  std::ifstream in(dir.path() / "out" / "metrics.jsonl");
  for (std::string line; std::getline(in, line);) {
    m.lines.push_back(nlohmann::json::parse(line));
    m.frames.push_back(m.lines.back()["frame"].get<int>());
  }
  return m;
}

// The farm finished every frame exactly once and correctly: one metrics line and one PNG
// per frame, and frames before, right after and long after the fault match tessera-render.
void expectEveryFrameOnceAndCorrect(const FarmDir& dir, const fs::path& scene, const MetricsLines& m,
                                    int frames = kFaultFrames) {
  std::vector<int> sorted = m.frames;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> expected(frames);
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(sorted, expected) << "each frame id must appear once in metrics.jsonl";
  for (int k = 0; k < frames; ++k) EXPECT_TRUE(fs::exists(dir.frame(k))) << "frame " << k;
  // The first frame issued under the last epoch was rendered after the fault.
  int after = frames - 1;
  const auto last_epoch = m.lines.back()["epoch"].get<int>();
  for (const auto& j : m.lines) {
    if (j["epoch"].get<int>() == last_epoch) after = std::min(after, j["frame"].get<int>());
  }
  for (int k : {0, after, (after + frames) / 2, frames - 1}) {
    if (!fs::exists(dir.frame(k))) continue;
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
  }
}

// Runs the default farm (2 renderers, 1 compositor) and calls `fault` once frame 1 is out.
CommandResult runWithFault(FarmDir& dir, const fs::path& scene, const std::function<void()>& fault,
                           int frames = kFaultFrames, const std::string& extra = "") {
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, frames, 240, extra); });
  if (!waitFor([&] { return fs::exists(dir.frame(1)); }, 60s)) {
    ADD_FAILURE() << "the farm produced no frame";
  } else {
    fault();
  }
  return farm.get();
}

// Every renderer reports stats for every frame, even one given no brick (0 active
// pixels). Two reports with pixel imbalance (max/mean) below 2 mean both drew something.
void expectTwoRenderersWorked(const nlohmann::json& frame) {
  EXPECT_EQ(frame["render_reports"].get<int>(), 2) << frame.dump();
  EXPECT_LT(frame["render_imbalance_pixels"].get<double>(), 1.9) << "a renderer drew nothing: " << frame.dump();
}

bool logHas(const FarmDir& dir, const std::string& text) { return dir.farmLog().find(text) != std::string::npos; }

// Well-formed parts from a process that never joined, for the frames in flight and claiming
// real ranks: before the roster they stalled the display (a forged Piece) or replaced real
// pixels (forged Strips). Now the data sockets take only roster members' connections.
TEST(FarmFaults, ForgedPartsFromNonMembersAreRefusedAndFramesStayCorrect) {
  FarmDir dir("forged");
  const int frames = 24;
  auto scene = dir.writeScene(frames, 40, 160, 120);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, frames, 180); });
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir.frame(1)); }, 60s)) << "the farm produced no frame";
  Image8 white(160, 120);
  std::fill(white.px.begin(), white.px.end(), 255);
  std::vector<std::vector<std::byte>> strips, pieces;
  for (uint64_t f = 2; f < frames; ++f)
    for (uint32_t epoch : {0u, 1u}) {
      proto::Strips st;
      st.frame = f;
      st.epoch = epoch;
      st.sender = 0;
      st.stream = encodeStrips(white, {0, 0, 160, 120}, 0);
      strips.push_back(proto::encode(st, 0, Codec::Lz4));
      proto::Piece pc;
      pc.frame = f;
      pc.epoch = epoch;
      pc.renderer = 0;
      pc.brick = 0;
      pc.region = {0, 0, 160, 120};
      pieces.push_back(proto::encode(pc, 0, Codec::Lz4));
    }
  zmq::context_t ctx;
  push(ctx, "ipc://" + (sockets / "display").string(), zmq::socket_type::dealer, strips);
  push(ctx, "ipc://" + (sockets / "compositor-0").string(), zmq::socket_type::dealer, pieces);

  auto run = farm.get();
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // 1/255: the sort-last contract; a forged white strip would be 255 levels off.
  for (int k = 0; k < frames; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
  EXPECT_NE(run.output.find("refused peer"), std::string::npos) << "refusals were not logged";
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  double composite = 0, display = 0;
  for (std::string line; std::getline(metrics, line);) {
    auto j = nlohmann::json::parse(line);
    composite = std::max(composite, j["composite_dropped"].get<double>());
    display = std::max(display, j["display_dropped"].get<double>());
  }
  EXPECT_GE(composite, (double)pieces.size()) << "forged pieces not counted";
  EXPECT_GE(display, (double)strips.size()) << "forged strips not counted";
}

// swap: the renderers composite by binary swap; the survivor waits for its dead partner's
// pieces until the master's new epoch, gets a new split of one brick (the whole volume) and
// sends the display its image alone, and swaps again once the restarted renderer has joined.
void expectKilledRendererReplaced(bool swap) {
  FarmDir dir(swap ? "kill-renderer-swap" : "kill-renderer");
  auto scene = dir.writeScene(kFaultFrames, 40, 160, 120);
  const fs::path sockets = dir.path() / "sockets";
  auto run = runWithFault(dir, scene, [&] {
    auto victims = farmPids(sockets, "tessera-renderer");
    ASSERT_EQ(victims.size(), 2u);
    ASSERT_EQ(kill(victims[0], SIGKILL), 0);
  }, kFaultFrames, swap ? "--env TESSERA_COMPOSITING=binary-swap" : "--env TESSERA_COMPOSITING=direct-send");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("died (signal 9); restarting (restart: on-failure, attempt 1)"), std::string::npos)
      << run.output;
  // Today's master marks the killed one lost and gives the restarted one a new rank.
  EXPECT_NE(run.output.find("renderer 2 joined"), std::string::npos) << run.output;
  // Its bricks went to a survivor, which loaded their voxels; no other brick moved then. With
  // binary swap, swapping needs one brick each: the survivor gets a new split of one brick,
  // or, if the restarted one joined before the loss was noticed, the two get a new split of two.
  const bool heir = run.output.find("of lost renderer") != std::string::npos;
  const bool resplit = run.output.find("binary swap: a new split of 1 bricks") != std::string::npos ||
                       run.output.find("binary swap: a new split of 2 bricks") != std::string::npos;
  EXPECT_TRUE(swap ? resplit && !heir : heir) << run.output;
  const auto m = readMetrics(dir);
  ASSERT_FALSE(m.lines.empty());
  expectEveryFrameOnceAndCorrect(dir, scene, m);
  // The last frame was rendered by two renderers again: the survivor and the restarted one.
  expectTwoRenderersWorked(m.lines.back());
  EXPECT_GT(m.lines.back()["epoch"].get<int>(), 0);
  if (!swap) return;
  // Both renderers said it at the start; the restarted one (and the survivor) again after.
  size_t said = 0;
  for (size_t at = 0; (at = run.output.find("binary swap among 2 renderers", at)) != std::string::npos; ++at) ++said;
  EXPECT_GE(said, 3u) << run.output;
}

TEST(FarmFaults, KilledRendererIsRestartedAndEveryFrameIsDoneOnce) { expectKilledRendererReplaced(false); }
TEST(FarmFaults, KilledSwapRendererIsRestartedAndEveryFrameIsDoneOnce) { expectKilledRendererReplaced(true); }

TEST(FarmFaults, KilledCompositorIsRestartedAndEveryFrameIsDoneOnce) {
  FarmDir dir("kill-compositor");
  auto scene = dir.writeScene(kFaultFrames, 40, 160, 120);
  const fs::path sockets = dir.path() / "sockets";
  auto run = runWithFault(dir, scene, [&] {
    auto victims = farmPids(sockets, "tessera-compositor");
    ASSERT_EQ(victims.size(), 1u);
    ASSERT_EQ(kill(victims[0], SIGKILL), 0);
  });
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("compositor died (signal 9); restarting (restart: on-failure, attempt 1)"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("compositor 1 joined"), std::string::npos) << run.output;
  const auto m = readMetrics(dir);
  ASSERT_FALSE(m.lines.empty());
  expectEveryFrameOnceAndCorrect(dir, scene, m);
  // The only compositor alive at the end is the restarted one, and it composited.
  EXPECT_EQ(m.lines.back()["composite_reports"].get<int>(), 1) << m.lines.back().dump();
  EXPECT_GT(m.lines.back()["epoch"].get<int>(), 0);
}

// A renderer frozen past the master's heartbeat timeout (3 s) is marked lost; once it
// resumes it must be given work again. Needs the master to re-admit a lost stage. A stage
// lost by the frame deadline is held out 5 s before it is re-admitted, so this run is long
// enough (about 20 s) for that to happen while frames are still being issued.
TEST(FarmFaults, FrozenRendererResumesAndGetsWorkAgain) {
  FarmDir dir("stop-renderer");
  constexpr int kFrames = 4 * kFaultFrames;
  // 320x240: at 160x120 the farm finished all frames (~7 s) before the 5 s hold-out ended.
  auto scene = dir.writeScene(kFrames, 40, 320, 240);
  const fs::path sockets = dir.path() / "sockets";
  auto run = runWithFault(dir, scene, [&] {
    auto victims = farmPids(sockets, "tessera-renderer");
    ASSERT_EQ(victims.size(), 2u);
    ASSERT_EQ(kill(victims[0], SIGSTOP), 0);
    // Whichever notices first marks it lost: 3 s without a heartbeat, or the frame deadline
    // (max(3 s, 8 x median latency)) passing while it holds stats back.
    const bool lost = waitFor([&] { return logHas(dir, "lost: no heartbeat") || logHas(dir, "missed its deadline"); }, 60s);
    ASSERT_EQ(kill(victims[0], SIGCONT), 0);
    ASSERT_TRUE(lost) << "the master never marked the frozen renderer lost";
    EXPECT_TRUE(waitFor([&] { return logHas(dir, "re-admitted"); }, 60s)) << "the resumed renderer was not re-admitted";
  }, kFrames);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(run.output.find("restarting"), std::string::npos) << "nothing died: " << run.output;
  const auto m = readMetrics(dir);
  ASSERT_FALSE(m.lines.empty());
  expectEveryFrameOnceAndCorrect(dir, scene, m, kFrames);
  SCOPED_TRACE("the resumed renderer must get work again");
  expectTwoRenderersWorked(m.lines.back());
}

// Without the master or the display the farm cannot go on: tessera-up says so and stops
// everything, leaving no process behind.
void expectFatalLoss(const std::string& name, const std::string& program) {
  FarmDir dir("kill-" + name);
  auto scene = dir.writeScene(1000, 40, 200, 200);
  const fs::path sockets = dir.path() / "sockets";
  auto farm = std::async(std::launch::async, [&] { return dir.runFarm(scene, 2, 1, 1000, 120); });
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir.frame(1)); }, 60s)) << "the farm produced no frame";
  auto victims = farmPids(sockets, program);
  ASSERT_EQ(victims.size(), 1u);
  ASSERT_EQ(kill(victims[0], SIGKILL), 0);
  ASSERT_EQ(farm.wait_for(60s), std::future_status::ready) << "the launcher did not stop the farm";
  auto run = farm.get();
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("tessera-up | " + name + " died (signal 9): the farm cannot continue without it; stopping"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(run.output.find("restarting"), std::string::npos) << "nothing is restarted while stopping: " << run.output;
  EXPECT_TRUE(waitFor([&] { return farmPids(sockets).empty(); }, 10s)) << "farm processes left behind";
}

// A scene the master cannot read ends the run before any frame: tessera-up exits non-zero, as
// tessera-render does, naming the voxel (it exited 0: the display finished cleanly first).
TEST(FarmFaults, AVolumeTheMasterCannotReadFailsTheRun) {
  FarmDir dir("unreadable");
  std::vector<float> v(8 * 8 * 8, 0.5f);
  v[3 + 8 * (2 + 8 * 1)] = std::numeric_limits<float>::quiet_NaN();
  std::ofstream(dir.path() / "nan.raw", std::ios::binary).write(reinterpret_cast<const char*>(v.data()), v.size() * 4);
  const fs::path scene = dir.path() / "nan.yaml";
  std::ofstream(scene) << "volume: {file: nan.raw, dims: [8, 8, 8], type: float32}\nimage: [40, 30]\n";
  const auto run = dir.runFarm(scene, 2, 1, 1, 60);
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("non-finite value nan at voxel (3, 2, 1)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("the run ended before this display showed a frame"), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("restarting"), std::string::npos) << "nothing is restarted: " << run.output;
}

TEST(FarmFaults, KilledMasterStopsTheFarmCleanly) { expectFatalLoss("master", "tessera-master"); }
TEST(FarmFaults, KilledDisplayStopsTheFarmCleanly) { expectFatalLoss("display", "tessera-display"); }

}  // namespace
}  // namespace tessera::test
