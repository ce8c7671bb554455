// Roster on the wire: only routing ids ZeroMQ can hold (1..255 bytes), nothing truncated.
#include <gtest/gtest.h>

#include "common/wire/protocol.h"

namespace tessera::proto {
namespace {

TEST(Protocol, RosterRejectsImpossibleRoutingIds) {
  auto empty = encode(Roster{1, {{Role::Renderer, 0, ""}}}, 1);
  auto r = decodeRoster(empty);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("members.identity"), std::string::npos) << r.error();
  auto huge = encode(Roster{1, {{Role::Renderer, 0, std::string(256, 'a')}}}, 1);
  EXPECT_FALSE(decodeRoster(huge));
  auto truncated = encode(Roster{1, {{Role::Renderer, 0, "abc"}}}, 1);
  truncated.resize(truncated.size() - 1);
  EXPECT_FALSE(decodeRoster(truncated));
}

}  // namespace
}  // namespace tessera::proto
