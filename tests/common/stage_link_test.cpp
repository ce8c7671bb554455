// A stage joining a master that is busy: the master of a big volume file without `range`
// reads the file for its range before it answers any Hello, and probes meanwhile. The
// master here is two raw sockets driven by the test, over ipc:// in a temporary folder.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "common/net/curve.h"
#include "common/net/stage_link.h"
#include "common/net/transport.h"
#include "tests/common/protocol_samples.h"
#include "tests/common/temp_dir.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
constexpr uint32_t kMaster = 0xFFFF;

struct FakeMaster {
  explicit FakeMaster(const std::string& name)
      : dir(name), ep(makeEndpoints("ipc://" + dir.file("s"))), pub(makeSocket(ctx, zmq::socket_type::pub)),
        ctl(makeSocket(ctx, zmq::socket_type::router)) {
    bindTo(pub, ep.masterPub());
    bindTo(ctl, ep.masterControl());
  }
  void probe() { sendBytes(pub, proto::encode(proto::Probe{}, kMaster)); }
  // Reads every Hello that came; returns the last sender's routing id ("" if none).
  std::string hellos(int* count) {
    std::string who;
    while (auto m = receiveRouted(ctl)) {
      if (m->has_body && proto::decodeHello(view(m->body))) who = m->identity, ++*count;
    }
    return who;
  }
  void send(const std::string& to, std::vector<std::byte>&& bytes) {
    ctl.send(zmq::buffer(to), zmq::send_flags::sndmore);
    sendBytes(ctl, std::move(bytes));
  }
  TempDir dir;
  Endpoints ep;
  zmq::context_t ctx;
  zmq::socket_t pub, ctl;
};

// Probes every 100 ms for `busy`, reading the Hellos but answering none, then welcomes the
// stage (twice: the answer to a Hello said again) after publishing one FrameParams.
void busyThenWelcome(FakeMaster& m, std::chrono::milliseconds busy, int* hellos) {
  std::string who;
  for (auto end = Clock::now() + busy; Clock::now() < end; std::this_thread::sleep_for(100ms)) {
    m.probe();
    if (auto w = m.hellos(hellos); !w.empty()) who = w;
  }
  for (auto end = Clock::now() + 2s; who.empty() && Clock::now() < end; std::this_thread::sleep_for(20ms)) {
    m.probe();
    who = m.hellos(hellos);
  }
  sendBytes(m.pub, proto::encode(proto::test::sampleParams(), kMaster));
  std::this_thread::sleep_for(50ms);  // the FrameParams reaches the stage before its Welcome
  for (int i = 0; i < 2; ++i) m.send(who, proto::encode(proto::Welcome{proto::Role::Renderer, 3, {0, 0}}, kMaster));
}

TEST(StageJoin, AStageWaitsForAMasterThatProbesLongerThanItsJoinWait) {
  FakeMaster m("join_busy");
  zmq::context_t ctx;
  StageLink link(ctx, m.ep, proto::Role::Renderer, "");
  int hellos = 0;
  auto master = std::async(std::launch::async, [&] { busyThenWelcome(m, 2500ms, &hellos); });
  const auto t0 = Clock::now();
  ASSERT_TRUE(link.join(nullptr, 1.0));  // a wait of 1 s, outlived by the busy master's 2.5 s
  EXPECT_GT(Clock::now() - t0, 2s);
  master.get();
  EXPECT_EQ(link.rank(), 3u);
  // Said again every quarter of the wait: a master restarted meanwhile would hear it.
  EXPECT_GE(hellos, 4);
  // What was published before the Welcome is not lost, and the repeated Welcome is no drop.
  std::this_thread::sleep_for(100ms);
  DropCounter drops;
  auto got = link.receive(drops);
  ASSERT_EQ(got.params.size(), 1u);
  EXPECT_EQ(got.params[0].frame, proto::test::sampleParams().frame);
  EXPECT_FALSE(link.receiveRoster(drops).has_value());
  EXPECT_EQ(drops.total(), 0u);
}

TEST(StageJoin, AStageGivesUpOnAMasterThatFallsSilent) {
  FakeMaster m("join_silent");
  zmq::context_t ctx;
  StageLink link(ctx, m.ep, proto::Role::Renderer, "");
  // Probes for 1.5 s, then nothing: the stage's 1 s wait runs from the last probe.
  auto master = std::async(std::launch::async, [&] {
    int hellos = 0;
    for (auto end = Clock::now() + 1500ms; Clock::now() < end; std::this_thread::sleep_for(100ms)) m.probe(), m.hellos(&hellos);
  });
  const auto t0 = Clock::now();
  EXPECT_FALSE(link.join(nullptr, 1.0));
  const auto waited = Clock::now() - t0;
  master.get();
  EXPECT_FALSE(link.runEnded());
  EXPECT_GT(waited, 2s);
  EXPECT_LT(waited, 4s);
}

TEST(StageJoin, AStageEndsItsWaitWhenTheMasterShutsDownBeforeItsWelcome) {
  FakeMaster m("join_shutdown");
  zmq::context_t ctx;
  StageLink link(ctx, m.ep, proto::Role::Compositor, "");
  // A master stopped while it read its volume: probes, then says Shutdown.
  auto master = std::async(std::launch::async, [&] {
    int hellos = 0;
    for (auto end = Clock::now() + 500ms; Clock::now() < end; std::this_thread::sleep_for(100ms)) m.probe(), m.hellos(&hellos);
    for (int i = 0; i < 5; ++i) sendBytes(m.pub, proto::encode(proto::Shutdown{"stopped while reading the volume", farmRun()}, kMaster));
  });
  const auto t0 = Clock::now();
  EXPECT_FALSE(link.join(nullptr, 30.0));
  master.get();
  EXPECT_LT(Clock::now() - t0, 10s) << "not the 30 s wait";
  EXPECT_TRUE(link.runEnded()) << "the run ended: the stage exits as stopped, not as failed";
}

// The master welcomes a spare and ends the run at once: its Shutdown (PUB) can overtake the
// Welcome (control connection). The stage joins and reads the Shutdown like every stage.
TEST(StageJoin, AStageWelcomedAsTheMasterShutsDownJoinsAndReadsTheShutdown) {
  FakeMaster m("join_welcome_shutdown");
  zmq::context_t ctx;
  StageLink link(ctx, m.ep, proto::Role::Renderer, "");
  auto master = std::async(std::launch::async, [&] {
    int hellos = 0;
    std::string who;
    for (auto end = Clock::now() + 3s; who.empty() && Clock::now() < end; std::this_thread::sleep_for(50ms))
      m.probe(), who = m.hellos(&hellos);
    sendBytes(m.pub, proto::encode(proto::Shutdown{"orbit done", farmRun()}, kMaster));
    std::this_thread::sleep_for(100ms);  // the Shutdown is read first
    m.send(who, proto::encode(proto::Welcome{proto::Role::Renderer, 4, {0, 0}}, kMaster));
  });
  ASSERT_TRUE(link.join(nullptr, 5.0));
  master.get();
  EXPECT_EQ(link.rank(), 4u);
  DropCounter drops;
  EXPECT_TRUE(link.receive(drops).shutdown);
  EXPECT_EQ(drops.total(), 0u);
}

// A master of another run that used this endpoint just before ours (its Shutdown said a few
// times as it exits) neither ends a joining stage's wait nor a joined stage's run; the joined
// stage counts it as a bad message.
TEST(StageJoin, AnotherRunsShutdownEndsNothing) {
  FakeMaster m("join_other_run");
  zmq::context_t ctx;
  StageLink link(ctx, m.ep, proto::Role::Renderer, "");
  const auto old = proto::encode(proto::Shutdown{"orbit done", farmRun() + "-yesterday"}, kMaster);
  int hellos = 0;
  auto master = std::async(std::launch::async, [&] {
    // While the stage waits for its Welcome (it said Hello), between probes.
    std::string who;
    for (auto end = Clock::now() + 3s; who.empty() && Clock::now() < end; std::this_thread::sleep_for(20ms))
      m.probe(), who = m.hellos(&hellos);
    for (int i = 0; i < 5; ++i) sendBytes(m.pub, std::vector<std::byte>(old)), std::this_thread::sleep_for(20ms), m.probe();
    std::this_thread::sleep_for(500ms);  // past the grace a Shutdown of its own run would start
    sendBytes(m.pub, proto::encode(proto::test::sampleParams(), kMaster));
    std::this_thread::sleep_for(50ms);
    m.send(who, proto::encode(proto::Welcome{proto::Role::Renderer, 3, {0, 0}}, kMaster));
    std::this_thread::sleep_for(50ms);
    sendBytes(m.pub, std::vector<std::byte>(old));  // and once joined
  });
  ASSERT_TRUE(link.join(nullptr, 5.0));
  master.get();
  EXPECT_FALSE(link.runEnded());
  std::this_thread::sleep_for(100ms);
  DropCounter drops;
  auto got = link.receive(drops);
  EXPECT_FALSE(got.shutdown);
  EXPECT_EQ(got.params.size(), 1u);
  EXPECT_EQ(drops.total(), 1u);
}

}  // namespace
}  // namespace tessera::test
