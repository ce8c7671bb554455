// Data-socket admission: only routing ids the latest roster names, with the right role; a
// message that overtakes its roster waits (bounded) and is admitted or dropped by the next.
#include "common/net/member_filter.h"

#include <optional>

#include <gtest/gtest.h>

namespace tessera {
namespace {

using proto::Role;

zmq::message_t body(size_t n) { return zmq::message_t(n); }

TEST(MemberFilter, OnlyRosterMembersOfTheSendingRoleHaveARank) {
  MemberFilter f({Role::Renderer}, 4, 1000);
  uint64_t dropped = 0;
  f.setRoster({1, {{Role::Renderer, 0, "r0"}, {Role::Renderer, 1, "r1"}, {Role::Compositor, 0, "c0"}}}, dropped);
  auto rank = [&](const char* id) { auto s = f.senderOf(id); return s ? std::optional<uint32_t>(s->rank) : std::nullopt; };
  EXPECT_EQ(rank("r1"), 1u);
  EXPECT_EQ(rank("r0"), 0u);
  EXPECT_FALSE(rank("c0")) << "a compositor may not send pieces";
  EXPECT_FALSE(rank("stranger"));
  f.setRoster({0, {{Role::Renderer, 0, "old"}}}, dropped);  // an older roster changes nothing
  EXPECT_EQ(rank("r1"), 1u);
  EXPECT_FALSE(rank("old"));
  f.setRoster({2, {{Role::Renderer, 0, "r0"}}}, dropped);  // r1 lost
  EXPECT_FALSE(rank("r1"));
}

// The display takes strips from compositors and a binary swap's bands from renderers: the
// role comes from the roster, so renderer 0 and compositor 0 are told apart.
TEST(MemberFilter, TwoRolesKeepTheirRanksApart) {
  MemberFilter f({Role::Compositor, Role::Renderer}, 4, 1000);
  uint64_t dropped = 0;
  f.setRoster({1, {{Role::Renderer, 0, "r0"}, {Role::Compositor, 0, "c0"}, {Role::Display, 0, "d"}}}, dropped);
  ASSERT_TRUE(f.senderOf("r0"));
  EXPECT_EQ(f.senderOf("r0")->role, Role::Renderer);
  ASSERT_TRUE(f.senderOf("c0"));
  EXPECT_EQ(f.senderOf("c0")->role, Role::Compositor);
  EXPECT_EQ(f.senderOf("c0")->rank, 0u);
  EXPECT_FALSE(f.senderOf("d")) << "the display sends nothing here";
}

TEST(MemberFilter, EarlyMessagesWaitBoundedThenTheNextRosterDecides) {
  MemberFilter f({Role::Compositor}, 3, 100);
  EXPECT_TRUE(f.hold("new", body(40)));
  EXPECT_TRUE(f.hold("stranger", body(40)));
  EXPECT_FALSE(f.hold("stranger", body(40))) << "byte budget exceeded";
  EXPECT_TRUE(f.hold("stranger", body(10)));
  EXPECT_FALSE(f.hold("stranger", body(1))) << "message budget exceeded";
  uint64_t dropped = 0;
  auto admitted = f.setRoster({5, {{Role::Compositor, 2, "new"}}}, dropped);
  ASSERT_EQ(admitted.size(), 1u);
  EXPECT_EQ(admitted[0].identity, "new");
  EXPECT_EQ(admitted[0].body.size(), 40u);
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(f.waiting(), 0u);
  EXPECT_TRUE(f.hold("late", body(100))) << "the budget is free again";
}

}  // namespace
}  // namespace tessera
