// The Hellos a master holds while it reads its volume (it cannot welcome anyone before it
// knows the range): the newest per connection, first come first; a stage silent since is
// left out; connections past the bound are not held. (The master handles every other
// control message then as always: strangers refused, bad messages dropped.)
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "master/preparation.h"

namespace tessera::master {
namespace {

using namespace std::chrono_literals;

TEST(HeldHellos, TheNewestHelloOfEachLiveConnectionFirstComeFirst) {
  HeldHellos held;
  auto hello = [&](char name, uint32_t pid) {
    return held.hold(std::string(16, name) + "c", proto::Hello{proto::Role::Renderer, pid, "", "run", ""});
  };
  EXPECT_TRUE(hello('e', 1));
  std::this_thread::sleep_for(150ms);
  EXPECT_TRUE(hello('g', 2));
  EXPECT_TRUE(hello('l', 3));
  std::this_thread::sleep_for(2500ms);
  EXPECT_TRUE(hello('e', 11));  // said again: the newest is kept, its place stays the first
  EXPECT_TRUE(hello('l', 13));
  std::this_thread::sleep_for(150ms);
  const auto live = held.live(1.5);  // `g` silent for 2.65 s, the others 0.15 s
  ASSERT_EQ(live.size(), 2u);
  EXPECT_EQ(live[0].first, std::string(16, 'e') + "c");
  EXPECT_EQ(live[0].second.pid, 11u);
  EXPECT_EQ(live[1].first, std::string(16, 'l') + "c");
  EXPECT_EQ(live[1].second.pid, 13u);
  EXPECT_TRUE(held.live(1.5).empty()) << "taken once";
}

TEST(HeldHellos, ConnectionsPastTheBoundAreNotHeld) {
  HeldHellos held;
  int accepted = 0;
  for (int i = 0; i < 5000; ++i)
    accepted += held.hold("stage-" + std::to_string(i), proto::Hello{proto::Role::Renderer, (uint32_t)i, "", "", ""});
  EXPECT_EQ(accepted, 4096);
  EXPECT_TRUE(held.hold("stage-7", proto::Hello{proto::Role::Renderer, 70, "", "", ""})) << "a held one says Hello again";
  EXPECT_EQ(held.live().size(), 4096u);
}

}  // namespace
}  // namespace tessera::master
