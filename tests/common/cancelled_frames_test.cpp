#include "common/wire/cancelled_frames.h"

#include <gtest/gtest.h>

namespace tessera {
namespace {

TEST(CancelledFrames, HoldsTheLatestRangesHalfOpenAndForgetsTheOldest) {
  CancelledFrames c;
  EXPECT_FALSE(c.contains(0)) << "nothing cancelled yet";
  c.add(5, 5);  // an empty range cancels nothing
  EXPECT_FALSE(c.contains(5));
  c.add(0, 2);
  EXPECT_TRUE(c.contains(0));
  EXPECT_TRUE(c.contains(1));
  EXPECT_FALSE(c.contains(2)) << "first_wanted itself is wanted";
  for (uint64_t k = 1; k <= 15; ++k) c.add(10 * k, 10 * k + 1);
  EXPECT_TRUE(c.contains(0)) << "16 ranges are kept";
  EXPECT_TRUE(c.contains(150));
  c.add(200, 201);
  EXPECT_FALSE(c.contains(0)) << "the 17th-newest range is forgotten";
  EXPECT_TRUE(c.contains(10));
}

}  // namespace
}  // namespace tessera
