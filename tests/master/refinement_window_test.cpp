// The colour window in the master's refinement: a right drag moves it, `r` and the scene's
// `window` are where it goes back to, and it stays within its bounds.
#include "master/refinement.h"

#include <gtest/gtest.h>

namespace tessera::master {
namespace {

using Clock = Refinement::Clock;

Refinement windowRefinement() { return Refinement(Camera{}, namedQuality(QualityName::Default), 1024, 768); }

proto::Input windowDrag(uint64_t seq, double shift, double scale, bool interacting = true) {
  proto::Input in;
  in.seq = seq;
  in.window_shift = shift;
  in.window_scale = scale;
  in.interacting = interacting;
  return in;
}

// A right-button drag moves the colour window: the level by widths, the width by a factor;
// the frames show it, the master says it once the drag ends, and r brings back the scene's.
TEST(Refinement, ARightDragMovesTheColourWindowAndRBringsBackTheScenes) {
  Refinement r = windowRefinement();
  auto t = Clock::now();
  r.issued(*r.next(t));
  EXPECT_FALSE(r.settledWindow(t)) << "the scene's window is not news";
  r.input(windowDrag(1, 0.25, 0.5), t);
  auto s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->interactive);
  EXPECT_EQ(s->window, (ColorWindow{0.75, 0.5}));  // the level moved by a quarter of the old width
  r.issued(*s);
  EXPECT_FALSE(r.settledWindow(t)) << "said while the drag goes on";
  r.input(windowDrag(2, 0, 1, false), t);  // released
  s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->interactive);
  EXPECT_EQ(s->window, (ColorWindow{0.75, 0.5}));
  r.issued(*s);
  EXPECT_EQ(r.settledWindow(t), (ColorWindow{0.75, 0.5}));
  EXPECT_FALSE(r.settledWindow(t)) << "said once";
  proto::Input home;
  home.seq = 3, home.home = true;
  r.input(home, t);
  s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->window, ColorWindow{});
  EXPECT_EQ(s->camera, Camera{});
}

// A scene's `window` is the first frames' and r's, and no news when a drag ends on it.
TEST(Refinement, TheScenesWindowIsWhereTheColourWindowStartsAndGoesBack) {
  Refinement r = windowRefinement();
  const ColorWindow scene{0.75, 0.25};  // binary fractions: the moves below are exact
  r.setSceneWindow(scene);
  auto t = Clock::now();
  auto s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->window, scene);
  r.issued(*s);
  EXPECT_FALSE(r.settledWindow(t));
  r.input(windowDrag(1, 0.5, 2, false), t);
  s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->window, (ColorWindow{0.875, 0.5}));
  r.issued(*s);
  proto::Input home;
  home.seq = 2, home.home = true;
  r.input(home, t);
  s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->window, scene);
}

TEST(Refinement, TheColourWindowStaysWithinItsBounds) {
  ColorWindow w;
  for (int i = 0; i < 20; ++i) w = Refinement::movedWindow(w, 0, 1000);  // each step at most 5 times
  EXPECT_EQ(w.width, Refinement::kMaxWindow);
  for (int i = 0; i < 20; ++i) w = Refinement::movedWindow(w, 0, 1e-3);
  EXPECT_EQ(w.width, Refinement::kMinWindow);
  w = Refinement::movedWindow({0.5, 0.5}, 100, 1);  // far above the values: an eighth stays over them
  EXPECT_DOUBLE_EQ(w.center, 1 + 0.5 * 3 / 8);
  w = Refinement::movedWindow({0.5, 0.5}, -100, 1);
  EXPECT_DOUBLE_EQ(w.center, -0.5 * 3 / 8);
  EXPECT_EQ(Refinement::movedWindow({3, 1e-9}, 0, 1), (ColorWindow{3, 1e-9})) << "no change: exactly as before";
  // A scene's window beyond the bounds does not jump there at a drag's first move.
  EXPECT_DOUBLE_EQ(Refinement::movedWindow({0.5, 1.0 / 4096}, 0, 2).width, 2.0 / 4096);
  EXPECT_DOUBLE_EQ(Refinement::movedWindow({0.5, 1.0 / 4096}, 0, 0.5).width, 1.0 / 4096);
  EXPECT_DOUBLE_EQ(Refinement::movedWindow({0.5, 64}, 0, 0.5).width, 32);
  EXPECT_DOUBLE_EQ(Refinement::movedWindow({5, 0.5}, 1, 1).center, 5);
  EXPECT_DOUBLE_EQ(Refinement::movedWindow({5, 0.5}, -1, 1).center, 4.5);
  Refinement r = windowRefinement();
  auto t = Clock::now();
  r.issued(*r.next(t));
  EXPECT_THROW(r.input(windowDrag(1, std::nan(""), 1), t), std::invalid_argument);
  EXPECT_THROW(r.input(windowDrag(2, 0, 0), t), std::invalid_argument);
  EXPECT_FALSE(r.next(t)) << "refused input changed the view";
}

TEST(Refinement, AMeshSceneHasNoColourWindow) {
  Scene scene;
  scene.mesh = MeshSpec{};
  Refinement r(scene);
  auto t = Clock::now();
  r.issued(*r.next(t));
  r.input(windowDrag(1, 0.25, 2, false), t);
  EXPECT_FALSE(r.next(t)) << "a mesh's colours do not change";
  EXPECT_EQ(r.window(), ColorWindow{});
}

}  // namespace
}  // namespace tessera::master
