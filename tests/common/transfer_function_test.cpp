// Transfer function evaluation, exact maximum opacity and opacity correction.
#include "common/transfer_function.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tessera;

namespace {
TransferFunction sample() {
  return TransferFunction({{0.2, 0.0, 0.0, 0.0, 0.0},
                           {0.4, 1.0, 0.5, 0.0, 0.8},
                           {0.6, 0.0, 1.0, 1.0, 0.2},
                           {0.6, 0.0, 0.0, 1.0, 0.6},  // a step at 0.6
                           {1.0, 1.0, 1.0, 1.0, 1.0}});
}
}  // namespace

TEST(TransferFunction, PiecewiseLinearAndClamped) {
  auto tf = sample();
  auto v = tf.eval(0.3);
  EXPECT_NEAR(v[0], 0.5, 1e-15);
  EXPECT_NEAR(v[1], 0.25, 1e-15);
  EXPECT_NEAR(v[3], 0.4, 1e-15);
  EXPECT_EQ(tf.eval(0.0)[3], 0.0);   // below the first point: its value
  EXPECT_EQ(tf.eval(-3.0)[3], 0.0);
  EXPECT_EQ(tf.eval(1.5)[3], 1.0);   // above the last
  EXPECT_EQ(tf.eval(0.4)[3], 0.8);   // exactly on a point
  EXPECT_NEAR(tf.eval(0.5)[3], 0.5, 1e-15);
  EXPECT_EQ(tf.eval(0.6)[3], 0.6);   // at a step the right-hand side applies
  EXPECT_NEAR(tf.eval(0.8)[3], 0.8, 1e-15);
  TransferFunction one({{0.5, 0.1, 0.2, 0.3, 0.4}});
  EXPECT_EQ(one.eval(0.9)[2], 0.3);
}

TEST(TransferFunction, MaxAlphaIsExact) {
  auto tf = sample();
  EXPECT_EQ(tf.maxAlpha(0.0, 0.2), 0.0);
  EXPECT_EQ(tf.maxAlpha(0.3, 0.5), 0.8);  // peak control point inside
  EXPECT_NEAR(tf.maxAlpha(0.25, 0.3), 0.4, 1e-15);
  EXPECT_NEAR(tf.maxAlpha(0.5, 0.45), 0.65, 1e-15);  // reversed bounds are accepted
  EXPECT_EQ(tf.maxAlpha(0.55, 0.6), 0.6);  // both sides of the step count
  EXPECT_NEAR(tf.maxAlpha(0.61, 0.7), 0.7, 1e-15);
  EXPECT_EQ(tf.maxAlpha(0.0, 1.0), 1.0);
}

TEST(TransferFunction, RejectsBadPoints) {
  EXPECT_THROW(TransferFunction(std::vector<TfPoint>{}), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5, 0, 0, 0, 0}, {0.4, 0, 0, 0, 0}}), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5, 1.5, 0, 0, 0}}), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{-0.1, 0, 0, 0, 0}}), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.1, 0, 0, 0, NAN}}), std::invalid_argument);
}

TEST(TransferFunction, CorrectOpacity) {
  for (double a : {1e-9, 0.01, 0.3, 0.9, 0.999999}) {
    EXPECT_NEAR(correctOpacity(a, kL0), a, 1e-15);
    // Two half steps absorb exactly what one full step does.
    double h = correctOpacity(a, kL0 / 2);
    EXPECT_NEAR(1 - (1 - h) * (1 - h), a, 1e-15 + 1e-12 * a);
    // Sixteen reference steps equal sixteen composited L0/16 steps (the reference quality).
    double s = correctOpacity(a, kL0 / 16), t = 1;
    for (int i = 0; i < 16; ++i) t *= 1 - s;
    EXPECT_NEAR(1 - t, a, 1e-14);
  }
  EXPECT_EQ(correctOpacity(0, kL0), 0);
  EXPECT_EQ(correctOpacity(1, kL0 / 16), 1);
  // Tiny opacity keeps its relative precision (a naive pow would lose it).
  EXPECT_NEAR(correctOpacity(1e-12, kL0 / 16) / (1e-12 / 16), 1.0, 1e-9);
}

TEST(TransferFunction, AWindowLaysTheMapOverPartOfTheValues) {
  const auto tf = sample();
  EXPECT_EQ(windowed(tf, {}), tf);  // the default window is the map itself
  // Narrow, wide, shifted past either end, and the step at 0.6 landing exactly on either edge.
  const double step_at = 0.6 - 0.5;  // the step's offset from the map's middle, as windowed() computes it
  ASSERT_EQ(1 - step_at + step_at, 1.0);
  for (ColorWindow w : {ColorWindow{0.5, 0.25}, ColorWindow{0.1, 0.5}, ColorWindow{0.9, 3}, ColorWindow{-0.2, 1},
                        ColorWindow{1.3, 2}, ColorWindow{0.4, 1}, ColorWindow{1 - step_at, 1}, ColorWindow{-step_at, 1}}) {
    const auto in = windowed(tf, w);
    EXPECT_EQ(in.points().front().s, 0.0);
    EXPECT_EQ(in.points().back().s, 1.0);
    for (int i = 0; i <= 1000; ++i) {
      const double s = i / 1000.0;
      const auto want = tf.eval((s - w.center) / w.width + 0.5), got = in.eval(s);
      for (int c = 0; c < 4; ++c)
        ASSERT_NEAR(got[c], want[c], 1e-12) << "window " << w.center << "/" << w.width << " at " << s << " channel " << c;
    }
  }
  // The map's points keep their colours, moved into the window.
  const auto half = windowed(tf, {0.25, 0.5});
  EXPECT_NEAR(half.points()[1].s, 0.1, 1e-15);  // 0.2 -> 0.25 + (0.2 - 0.5) * 0.5
  EXPECT_EQ(half.points()[2].a, 0.8);
  EXPECT_THROW(windowed(tf, {0.5, 0}), std::invalid_argument);
  EXPECT_THROW(windowed(tf, {std::nan(""), 1}), std::invalid_argument);
  // The range a scene gives for it: a window of a CT range.
  const auto r = windowRange({-1000, 3000}, {0.25, 0.1});
  EXPECT_DOUBLE_EQ(r[0], -200);
  EXPECT_DOUBLE_EQ(r[1], 200);
}
