// The Hellos a master holds while it reads its volume (it cannot welcome anyone before it
// knows the range): the newest per connection, first come first; a stage silent since is
// left out; anything else is dropped and counted. Real sockets over ipc:// in a temp folder.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/net/transport.h"
#include "master/preparation.h"
#include "tests/common/temp_dir.h"

namespace tessera::master {
namespace {

using namespace std::chrono_literals;

TEST(HeldHellos, TheNewestHelloOfEachLiveConnectionFirstComeFirst) {
  test::TempDir dir("held_hellos");
  const std::string at = "ipc://" + dir.file("ctl");
  zmq::context_t ctx;
  zmq::socket_t router = makeSocket(ctx, zmq::socket_type::router);
  router.bind(at);
  auto stage = [&](char name) {
    zmq::socket_t s = makeSocket(ctx, zmq::socket_type::dealer);
    s.set(zmq::sockopt::routing_id, std::string(16, name) + "c");
    s.connect(at);
    return s;
  };
  zmq::socket_t gone = stage('g'), late = stage('l'), early = stage('e');
  auto hello = [](zmq::socket_t& s, uint32_t pid) {
    sendBytes(s, proto::encode(proto::Hello{proto::Role::Renderer, pid, "", "run"}, 0));
  };
  HeldHellos held;
  DropCounter drops;
  std::vector<std::string> refused;
  const HeldHellos::Refuse refuse = [&](const std::string& why) { refused.push_back(why); };
  auto holdFor = [&](std::chrono::milliseconds t) {
    for (auto end = std::chrono::steady_clock::now() + t; std::chrono::steady_clock::now() < end;) {
      held.hold(router, drops, refuse);
      std::this_thread::sleep_for(20ms);
    }
  };
  hello(early, 1);
  holdFor(150ms);
  hello(gone, 2);
  hello(late, 3);
  sendBytes(gone, std::vector<std::byte>(20, std::byte{7}));  // junk: dropped, counted
  // A stage of no one's (none has joined yet): refused, not held.
  sendBytes(gone, proto::encode(proto::Heartbeat{proto::Role::Renderer, 0}, 0));
  holdFor(2500ms);
  hello(early, 11);  // said again: the newest is kept, its place stays the first
  hello(late, 13);
  holdFor(150ms);
  const auto live = held.live(router, drops, refuse, 1.5);  // `gone` silent for 2.65 s, the others 0.15 s
  ASSERT_EQ(live.size(), 2u);
  EXPECT_EQ(live[0].first, std::string(16, 'e') + "c");
  EXPECT_EQ(live[0].second.pid, 11u);
  EXPECT_EQ(live[1].first, std::string(16, 'l') + "c");
  EXPECT_EQ(live[1].second.pid, 13u);
  EXPECT_EQ(drops.total(), 1u);
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0], "while reading the volume: unknown peer sent Heartbeat");
  EXPECT_TRUE(held.live(router, drops, refuse, 1.5).empty()) << "taken once";
}

}  // namespace
}  // namespace tessera::master
