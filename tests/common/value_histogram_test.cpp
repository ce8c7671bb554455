// The histogram tessera-info prints and the `range` it suggests.
#include "common/value_histogram.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tessera {
namespace {

// Values read back from normalised floats land a rounding below an integer: each is still
// counted in the bin whose lower edge it is (0..255 in 16 bins of 15.9375: 0 and 255 only
// sit on edges, so use 0..160 in 16 bins of 10).
TEST(ValueHistogram, AnIntegerOnABinsLowerEdgeIsInThatBin) {
  ValueHistogram h(0, 160, 16, true);
  for (int v = 0; v <= 160; ++v) h.add(v * (1 - 1e-7f));  // as a float32 round trip may give them
  for (size_t b = 0; b < 15; ++b) EXPECT_EQ(h.counts[b], 10u) << b;
  EXPECT_EQ(h.counts[15], 11u) << "the last bin includes the maximum";
  // The same for integers with no rounding error and an edge that is not an integer.
  ValueHistogram odd(0, 255, 16, true);
  for (int v = 0; v <= 255; ++v) odd.add(v);
  uint64_t sum = 0;
  for (size_t b = 0; b < 16; ++b) {
    const uint64_t expected = (uint64_t)(std::floor(odd.edge(b + 1) - 1e-9) - std::ceil(odd.edge(b)) + 1) + (b == 15);
    EXPECT_EQ(odd.counts[b], expected) << b;
    sum += odd.counts[b];
  }
  EXPECT_EQ(sum, 256u);
}

// A NIfTI scale of 0.01 makes an int16 file's values decimals: they must not be rounded.
TEST(ValueHistogram, ScaledIntegersAreIntegersOnlyWithAnIntegerScale) {
  RawVolumeSpec s;
  s.type = VoxelType::Int16;
  EXPECT_TRUE(storesIntegers(s));
  s.slope = 2, s.inter = -1024;
  EXPECT_TRUE(storesIntegers(s));
  s.slope = 0.01;
  EXPECT_FALSE(storesIntegers(s));
  s.slope = 1, s.inter = 0.5;
  EXPECT_FALSE(storesIntegers(s));
  s.inter = 0, s.type = VoxelType::Float32;
  EXPECT_FALSE(storesIntegers(s));
}

ValueHistogram fine(double lo, double hi) { return ValueHistogram(lo, hi, 4096, true); }

void addRun(ValueHistogram& h, int from, int to, uint64_t each) {
  for (int v = from; v <= to; ++v)
    for (uint64_t k = 0; k < each; ++k) h.add(v);
}

// A CT scan: -3024 outside the scanner's circle (a fifth of the voxels), air to bone inside.
TEST(SuggestedRange, CtPaddingIsLeftOut) {
  ValueHistogram h = fine(-3024, 1500);
  h.counts[0] = 200000;
  addRun(h, -1024, 1500, 300);
  const auto a = suggestedRange(h);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->range[0], -1024);
  EXPECT_EQ(a->range[1], 1500);
  EXPECT_NE(a->why.find("lie apart below the rest, at -3024"), std::string::npos) << a->why;
  EXPECT_NEAR(a->inside, 757500.0 / 957500, 1e-9);
}

// Hot voxels far above the rest, and a thin tail: both left out; a tail alone must make the
// range under half the span to be said.
TEST(SuggestedRange, OutliersAndThinTailsAreLeftOut) {
  ValueHistogram hot = fine(0, 4095);
  addRun(hot, 0, 799, 1000);
  hot.add(4095), hot.add(4095), hot.add(4000);
  const auto a = suggestedRange(hot);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->range[0], 0);
  EXPECT_EQ(a->range[1], 799);
  EXPECT_NE(a->why.find("above the rest, at 4000 .. 4095"), std::string::npos) << a->why;
  ValueHistogram tail = fine(0, 10000);
  addRun(tail, 0, 999, 1000);
  for (int v = 1000; v <= 10000; v += 100) tail.add(v);  // 91 voxels: under 0.01%, and no gap
  const auto t = suggestedRange(tail);
  ASSERT_TRUE(t);
  EXPECT_GE(t->range[1], 999);
  EXPECT_LE(t->range[1], 1002) << "bins of 10000/4096: 999 shares one with 1000 and 1001";
  EXPECT_EQ(t->why, "the rest are a thin tail");
}

// Hot voxels so far above the rest that the data fills only a few of the bins: not labels
// (found by review: 5 voxels at 60000 over data in 0..100 got no advice, in 0..300 they did).
TEST(SuggestedRange, HotVoxelsFarAboveAFewBinsOfDataAreLeftOut) {
  for (bool integral : {false, true}) {
    ValueHistogram h(0, 60000, 4096, integral);
    for (int v = 0; v < 100; ++v)
      for (int k = 0; k < 300; ++k) h.add(v + (integral ? 0 : k / 300.0));
    for (int k = 0; k < 5; ++k) h.add(60000);
    const auto a = suggestedRange(h);
    ASSERT_TRUE(a) << "integral " << integral;
    EXPECT_EQ(a->range[0], 0);
    EXPECT_GE(a->range[1], 100) << "the data's bins: 60000/4096 wide";
    EXPECT_LE(a->range[1], 115);
    EXPECT_NE(a->why.find("above the rest, at 599"), std::string::npos) << a->why;  // the top bin, 59985.35 .. 60000
  }
}

// Gaps in real data (bone far above soft tissue), data that fills its span, and labels.
TEST(SuggestedRange, DataOfItsOwnIsLeftAlone) {
  ValueHistogram gap = fine(-1000, 1500);
  addRun(gap, -1000, -900, 100);
  addRun(gap, 0, 100, 1000);
  addRun(gap, 1200, 1500, 20);  // 5% of the voxels beyond a gap of half the span
  EXPECT_FALSE(suggestedRange(gap));
  ValueHistogram plain = fine(0, 255);
  addRun(plain, 0, 255, 50);
  EXPECT_FALSE(suggestedRange(plain));
  ValueHistogram labels = fine(0, 3000);
  for (int v : {0, 0, 0, 0, 0, 0, 0, 0, 0, 1000, 3000}) addRun(labels, v, v, 1000);
  EXPECT_FALSE(suggestedRange(labels));
  // Labels spread wider than the bins, and a float mask with a rare label (a lesion).
  ValueHistogram wide = fine(0, 5000);
  for (int v : {0, 17, 5000}) addRun(wide, v, v, v == 0 ? 100000 : 10);
  EXPECT_FALSE(suggestedRange(wide));
  ValueHistogram mask(0, 1, 4096, false);
  for (int k = 0; k < 200000; ++k) mask.add(k % 2000 == 0 ? 1.0 : 0.0);
  EXPECT_FALSE(suggestedRange(mask)) << "a mask's rare ones were advised out of the range";
}

}  // namespace
}  // namespace tessera
