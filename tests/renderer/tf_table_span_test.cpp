// The classification table spans only where the map varies (TfTable, TransferFunction::
// variedSpan): a narrow colour window gets every entry, and renders as the reference does
// (a window of 1/200 of the range had 20 entries and 30 dB: found by review).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "common/bricks.h"
#include "common/image.h"
#include "renderer/volume/raycaster.h"
#include "renderer/volume/tf_table.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

TEST(TfTableSpan, AMapOverAllOfTheRangeKeepsTheTableItHad) {
  // What every shipped scene's map has: the same table, the same positions (bit-identical images).
  const TfTable t(test::defaultTf(), kL0);
  EXPECT_EQ(t.scale(), 4095.0f);
  EXPECT_EQ(t.offset(), 0.0f);
  EXPECT_EQ(test::defaultTf().variedSpan(), (std::array<double, 2>{0, 1}));
  const TransferFunction flat({{0, 1, 1, 1, 0.5}, {1, 1, 1, 1, 0.5}});
  EXPECT_EQ(flat.variedSpan(), (std::array<double, 2>{0, 1}));
  const TransferFunction step({{0, 0, 0, 0, 0}, {0.5, 0, 0, 0, 0}, {0.5, 1, 1, 1, 1}, {1, 1, 1, 1, 1}});
  EXPECT_EQ(step.variedSpan(), (std::array<double, 2>{0, 1})) << "a step at one scalar has no span";
}

TEST(TfTableSpan, ANarrowWindowGetsEveryEntry) {
  const ColorWindow w{0.4, 0.005};
  const TransferFunction tf = windowed(test::defaultTf(), w);
  const auto span = tf.variedSpan();
  EXPECT_NEAR(span[0], 0.3975, 1e-12);
  EXPECT_NEAR(span[1], 0.4025, 1e-12);
  const TfTable t(tf, kL0);
  // Within the window (and a tenth beyond each side) the lookup errs as the whole map's table
  // does over the whole range (raycaster_test: TfTable.ErrorAgainstExactClassificationIsSmall).
  const double worst = test::tableError(t, tf, 0.3975 - 0.0005, 0.4025 + 0.0005, 12000);
  EXPECT_LT(worst, 1.5e-4);
}

// A step at the low end of where the map varies (transparent below 0.5, then a ramp): the
// values below the step keep the value below it (they took the one above, air turned opaque
// red: found by review), with and without empty-space skipping.
TEST(TfTableSpan, AStepAtTheSpansLowEndKeepsTheValueBelowIt) {
  const TransferFunction tf({{0, 0, 0, 0, 0}, {0.5, 0, 0, 0, 0}, {0.5, 1, 0.2, 0.2, 0.05}, {1, 1, 1, 0.2, 0.1}});
  EXPECT_LT(tf.variedSpan()[0], 0.5);
  const TfTable t(tf, kL0);
  for (float s : {0.0f, 0.3f, 0.4998f}) {
    float out[4];
    t.lookup(s, out);
    EXPECT_EQ(out[3], 0.0f) << s;
  }
  auto vol = test::generated("marschner-lobb", 40);
  const Raycaster rc(vol, tf);
  const ImageF ref = rc.render(test::defaultCamera(), 48, 48, wholeVolume(*vol), test::options("reference"));
  for (bool skip : {true, false}) {
    RenderOptions o = test::options("default");
    o.quality.skip_empty = skip;
    const ImageError e = compare(rc.render(test::defaultCamera(), 48, 48, wholeVolume(*vol), o), ref);
    EXPECT_GE(e.psnr, 40.0) << "skip " << skip << " max_abs " << e.max_abs;
  }
}

// A smooth ball whose values fill only 1/200 of the mapped range (a CT's soft tissue in its
// whole HU range, say), seen through a window on them: before, 20 table entries (30 dB).
TEST(TfTableSpan, ANarrowWindowRendersAsTheReferenceDoes) {
  auto ball = std::make_shared<Volume>();
  constexpr int n = 40;
  ball->dims = {n, n, n};
  ball->values.resize((size_t)n * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double r = std::hypot(x - 19.5, y - 19.5, z - 19.5);
        ball->values[ball->index(x, y, z)] = (float)(0.4 + 0.005 * std::clamp((19.5 - r) / 16, 0.0, 1.0));
      }
  const TransferFunction kinked({{0, 0, 0, 0, 0}, {0.4, 0.2, 0.5, 1, 0}, {0.6, 1, 0.8, 0.3, 0.5}, {1, 1, 1, 1, 0.9}});
  const Raycaster rc(ball, windowed(kinked, ColorWindow{0.4025, 0.005}));
  const ImageF def = rc.render(test::defaultCamera(), 48, 48, wholeVolume(*ball), test::options("default"));
  const ImageF ref = rc.render(test::defaultCamera(), 48, 48, wholeVolume(*ball), test::options("reference"));
  ASSERT_GT(activeRegion(ref).area(), 400);  // the window shows the ball
  const ImageError e = compare(def, ref);
  EXPECT_GE(e.psnr, 45.0) << "max_abs " << e.max_abs;
}

}  // namespace
}  // namespace tessera::renderer
