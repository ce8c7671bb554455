#include "master/refinement.h"

#include "master/interaction.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tessera::master {
namespace {

using Clock = Refinement::Clock;
using std::chrono::milliseconds;

proto::Input drag(uint64_t seq, double dx) {
  proto::Input in;
  in.seq = seq;
  in.orbit_dx = dx;
  in.interacting = true;
  return in;
}

Refinement make() { return Refinement(Camera{}, namedQuality(QualityName::Default), 1024, 768); }

TEST(Refinement, FirstFrameIsFullThenNothingUntilInput) {
  Refinement r = make();
  const auto t0 = Clock::now();
  auto s = r.next(t0);
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->interactive);
  EXPECT_EQ(s->width, 1024);
  EXPECT_EQ(s->height, 768);
  r.issued(*s);
  EXPECT_FALSE(r.next(t0 + milliseconds(1000))) << "nothing changed: no frame";
}

TEST(Refinement, ADragGivesReducedFramesOfTheNewestCameraThenTheFullOneOnRelease) {
  Refinement r = make();
  auto t = Clock::now();
  r.issued(*r.next(t));
  for (uint64_t k = 1; k <= 200; ++k) r.input(drag(k, 0.5), t);  // a burst: one frame, not 200
  auto s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->interactive);
  EXPECT_EQ(s->input_seq, 200u);
  EXPECT_EQ(s->reduction, Refinement::kReductions[Refinement::kStartLevel]);
  EXPECT_EQ(s->width, 512);
  EXPECT_EQ(s->height, 384);
  EXPECT_EQ(s->full_width, 1024);
  EXPECT_EQ(s->quality.step, 2 * namedQuality(QualityName::Default).step);
  r.issued(*s);
  EXPECT_FALSE(r.next(t)) << "the newest camera is already issued";
  proto::Input release;
  release.seq = 201;
  r.input(release, t + milliseconds(10));
  auto sharp = r.next(t + milliseconds(10));
  ASSERT_TRUE(sharp);
  EXPECT_FALSE(sharp->interactive);
  EXPECT_EQ(sharp->camera, s->camera) << "the full frame shows the final camera";
  EXPECT_EQ(sharp->width, 1024);
  EXPECT_EQ(sharp->quality, namedQuality(QualityName::Default));
  EXPECT_EQ(sharp->input_seq, 201u);
}

// A scene's `quality: {jitter: true}` holds for the moving frames and through the quality keys
// (they pick a preset's step; the reference samples mid-step, as it always does).
TEST(Refinement, TheScenesJitterStaysThroughDragsAndQualityKeys) {
  Quality jittered = namedQuality(QualityName::Default);
  jittered.name = QualityName::Custom;
  jittered.jitter = true;
  Refinement r(Camera{}, jittered, 1024, 768);
  auto t = Clock::now();
  r.issued(*r.next(t));
  r.input(drag(1, 0.5), t);
  auto moving = r.next(t);
  ASSERT_TRUE(moving && moving->interactive);
  EXPECT_TRUE(moving->quality.jitter);
  r.issued(*moving);
  // Pressing a quality key: the full frame it asks for (issued).
  const auto press = [&](uint64_t seq, QualityName q) {
    proto::Input key;
    key.seq = seq;
    key.quality = q;
    r.input(key, t + milliseconds(10 * seq));
    auto s = r.next(t + milliseconds(10 * seq));
    EXPECT_TRUE(s && !s->interactive);
    if (s) r.issued(*s);
    return s ? s->quality : Quality{};
  };
  const Quality fast = press(2, QualityName::Fast);
  EXPECT_TRUE(fast.jitter);
  EXPECT_EQ(fast.step, namedQuality(QualityName::Fast).step);
  EXPECT_EQ(press(3, QualityName::Reference), namedQuality(QualityName::Reference));
  EXPECT_TRUE(press(4, QualityName::Default).jitter) << "the scene's jitter, not the reference's mid-step";
}

TEST(Refinement, AHeldButStillMouseGetsTheFullFrameAfterThePause) {
  Refinement r = make();
  auto t = Clock::now();
  r.input(drag(1, 3), t);
  EXPECT_TRUE(r.interacting(t + milliseconds(100)));
  EXPECT_FALSE(r.interacting(t + milliseconds((int)Refinement::kStillAfterMs + 1)));
  r.issued(*r.next(t));
  auto s = r.next(t + milliseconds((int)Refinement::kStillAfterMs + 1));
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->interactive);
}

TEST(Refinement, TheRungFollowsTheMeasuredLatency) {
  Refinement r = make();
  auto t = Clock::now();
  r.input(drag(1, 1), t);
  auto s = *r.next(t);
  r.interactiveDone(s, Refinement::kTargetMs * 2);  // too slow: one rung cheaper
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel + 1]);
  r.interactiveDone(s, 1);  // feedback of the old rung does not count
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel + 1]);
  s = *r.next(t);
  r.interactiveDone(s, 10);  // fast: the pixel count may grow within the target
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]);
  s = *r.next(t);
  r.interactiveDone(s, Refinement::kTargetMs);  // on target: stays
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]);
}

TEST(Refinement, ARungThatSavesNothingIsNotKept) {
  // A mesh: its cost is in its triangles, not its pixels; fewer pixels save nothing.
  Refinement r = make();
  auto t = Clock::now();
  r.input(drag(1, 1), t);
  const double slow = Refinement::kTargetMs * 2;
  r.interactiveDone(*r.next(t), slow);
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel + 1]) << "too slow: one rung cheaper";
  r.interactiveDone(*r.next(t), slow);
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]) << "no faster: back to the dearer rung";
  for (int i = 0; i < 5; ++i) r.interactiveDone(*r.next(t), slow);
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]) << "and it stays there";
}

TEST(Refinement, ANewDragForgetsWhatTheRungsCostInTheLastOne) {
  // The scene or the window may have changed between drags: a rung once useless is tried again.
  Refinement r = make();
  auto t = Clock::now();
  r.input(drag(1, 1), t);
  const double slow = Refinement::kTargetMs * 2;
  r.interactiveDone(*r.next(t), slow);
  r.interactiveDone(*r.next(t), slow);
  ASSERT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]) << "back on the dearer rung";
  proto::Input release;
  release.seq = 2;
  r.input(release, t);
  t += milliseconds(2000);
  r.input(drag(3, 1), t);
  r.interactiveDone(*r.next(t), slow);
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel + 1]) << "the cheaper rung is tried again";
}

TEST(Refinement, AFrameIssuedBehindACancelledFullFrameDoesNotMoveTheRung) {
  // Its time includes the wait for the renderers to finish the cancelled frame.
  Refinement r = make();
  auto t = Clock::now();
  r.input(drag(1, 1), t);
  auto s = *r.next(t);
  s.after_cancel = true;
  r.interactiveDone(s, Refinement::kTargetMs * 4);
  EXPECT_EQ(r.reduction(), Refinement::kReductions[Refinement::kStartLevel]);
}

TEST(Refinement, InputToPresentStartsAtTheFirstInputThatChangesTheView) {
  Refinement r = make();
  auto t = Clock::now();
  r.issued(*r.next(t));
  proto::Input still;  // no motion, no drag: the view stays
  still.seq = 1;
  r.input(still, t);
  EXPECT_FALSE(r.next(t));
  r.input(drag(2, 1), t);
  r.input(drag(3, 1), t);
  auto s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->input_first, 2u) << "input 1 changed nothing";
  EXPECT_EQ(s->input_seq, 3u);
  r.issued(*s);
  EXPECT_FALSE(r.next(t)) << "the answer to input 2 is not a new view";
  r.input(drag(4, 1), t);
  s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->input_first, 4u) << "the next frame answers the inputs after the last frame issued";
}

TEST(Refinement, AResizedWindowIsRenderedAtItsShapeWithinTheScenesImage) {
  EXPECT_EQ(Refinement::fitWindow(800, 600, 1024, 768), std::make_pair(800, 600));
  EXPECT_EQ(Refinement::fitWindow(2048, 768, 1024, 768), std::make_pair(1024, 384));
  EXPECT_EQ(Refinement::fitWindow(1, 5000, 1024, 768), std::make_pair(1, 768));
  Refinement r = make();
  auto t = Clock::now();
  r.issued(*r.next(t));
  proto::Input in;
  in.width = 640;
  in.height = 640;
  r.input(in, t);
  auto s = r.next(t);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->width, 640);
  EXPECT_EQ(s->height, 640);
}

TEST(Refinement, RefusedInputChangesNothing) {
  Refinement r = make();
  auto t = Clock::now();
  r.issued(*r.next(t));
  proto::Input bad;
  bad.zoom = -1;
  bad.interacting = true;
  EXPECT_THROW(r.input(bad, t), std::invalid_argument);
  EXPECT_FALSE(r.interacting(t));
  EXPECT_FALSE(r.next(t));
}

// The window's r: the scene's camera again, whatever the drags did; a drag in the same input
// turns from there.
TEST(Refinement, HomeGoesBackToTheScenesCamera) {
  const Camera scene{{0.3, 0.5, 2.5}, {0, 0, 0}, {0, 1, 0}, 30, false, 1};
  Refinement r(scene, namedQuality(QualityName::Default), 640, 480);
  auto t = Clock::now();
  auto camera = [&] {  // the next frame's camera, issued
    const auto s = r.next(t);
    EXPECT_TRUE(s.has_value());
    if (!s) return Camera{};
    r.issued(*s);
    return s->camera;
  };
  EXPECT_EQ(camera(), scene);
  for (uint64_t k = 1; k <= 3; ++k) r.input(drag(k, 25), t);
  proto::Input zoom;
  zoom.seq = 4, zoom.zoom = 0.5;
  r.input(zoom, t);
  EXPECT_FALSE(camera() == scene);
  proto::Input home;
  home.seq = 5, home.home = true;
  r.input(home, t);
  EXPECT_EQ(camera(), scene);
  r.input(drag(6, 40), t);
  proto::Input both = drag(7, 25);
  both.home = true;
  r.input(both, t);
  EXPECT_EQ(camera(), applyInput(scene, drag(8, 25)));
}

// A scene without `camera` is fitted to its image at the start; its r fits the box to the
// window's shape at that moment, so a window made tall shows the whole box again.
TEST(Refinement, HomeFitsASceneWithoutCameraToTheWindowsShape) {
  Scene scene = parseScene("volume: {generator: {name: hollow-shell, size: 16}}\nimage: [640, 480]\n", ".");
  ASSERT_TRUE(scene.camera_fitted);
  Refinement r(scene);
  auto t = Clock::now();
  auto camera = [&] {
    const auto s = r.next(t);
    EXPECT_TRUE(s.has_value());
    if (!s) return Camera{};
    r.issued(*s);
    return s->camera;
  };
  EXPECT_EQ(camera(), fittedCamera(scene, 640.0 / 480));
  proto::Input tall = drag(1, 30);
  tall.width = 240, tall.height = 480;
  r.input(tall, t);
  (void)camera();
  proto::Input home;
  home.seq = 2, home.home = true;
  r.input(home, t);
  const Camera fitted = fittedCamera(scene, 240.0 / 480);
  EXPECT_EQ(camera(), fitted);
  EXPECT_FALSE(fitted == fittedCamera(scene, 640.0 / 480)) << "the test cannot tell the two shapes apart";
  // A scene's own camera stays as it is.
  scene.camera_fitted = false;
  Refinement fixed(scene);
  fixed.input(tall, t);
  fixed.input(home, t);
  ASSERT_TRUE(fixed.next(t));
  EXPECT_EQ(fixed.next(t)->camera, scene.camera);
}

proto::Input key(uint64_t seq, proto::TimeKey k) {
  proto::Input in;
  in.seq = seq;
  in.time = k;
  return in;
}

// Issues frames while there are new ones (at most `max`) and returns their steps.
std::vector<int> play(Refinement& r, int max) {
  std::vector<int> steps;
  for (int i = 0; i < max; ++i) {
    auto s = r.next(Clock::now());
    if (!s) break;
    steps.push_back(s->step);
    r.issued(*s);
  }
  return steps;
}

TEST(Refinement, ASeriesPlaysPausesAndStepsOnTheNextFrame) {
  Playback p;
  p.play = true;
  Refinement r(Camera{}, namedQuality(QualityName::Default), 64, 64, p, 5);
  auto s = r.next(Clock::now());
  ASSERT_TRUE(s);
  EXPECT_EQ(s->next_step, 1) << "renderers prefetch the step after";
  EXPECT_EQ(play(r, 7), (std::vector<int>{0, 1, 2, 3, 4, 0, 1}));
  r.input(key(1, proto::TimeKey::PlayPause), Clock::now());  // pause: the step the next frame would show stays
  EXPECT_EQ(play(r, 7), (std::vector<int>{2}));
  r.input(key(2, proto::TimeKey::Back), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{1}));
  r.input(key(3, proto::TimeKey::Back), Clock::now());
  r.input(key(4, proto::TimeKey::Back), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{4})) << "stepping wraps around";
  r.input(key(5, proto::TimeKey::First), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{0}));
  r.input(key(6, proto::TimeKey::Last), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{4}));
  r.input(key(7, proto::TimeKey::Forward), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{0}));
  r.input(key(8, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 3), (std::vector<int>{1, 2, 3})) << "plays on after the step shown";
}

TEST(Refinement, AFinishedOncePlaysAgainFromTheStart) {
  Playback p;
  p.play = true;
  p.mode = Playback::Mode::Once;
  Refinement r(Camera{}, namedQuality(QualityName::Default), 64, 64, p, 3);
  EXPECT_EQ(play(r, 9), (std::vector<int>{0, 1, 2})) << "once: no frame after the last step";
  r.input(key(1, proto::TimeKey::PlayPause), Clock::now());  // one press: from the start again
  EXPECT_EQ(play(r, 9), (std::vector<int>{0, 1, 2})) << "a press after the end played nothing (found by review)";
  r.input(key(2, proto::TimeKey::Back), Clock::now());  // paused on step 1
  EXPECT_EQ(play(r, 9), (std::vector<int>{1}));
  r.input(key(3, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 9), (std::vector<int>{2})) << "a paused once plays on from where it is";
  // Space one frame before the end pauses: it does not start again (found by review).
  Refinement q(Camera{}, namedQuality(QualityName::Default), 64, 64, p, 5);
  EXPECT_EQ(play(q, 4), (std::vector<int>{0, 1, 2, 3}));
  q.input(key(1, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(q, 9), (std::vector<int>{4})) << "paused: the step the next frame would show";
}

// A swing paused on its way back resumed forwards (found by review).
TEST(Refinement, APausedSwingGoesOnTheWayItWent) {
  Playback p;
  p.play = true;
  p.mode = Playback::Mode::Swing;
  Refinement r(Camera{}, namedQuality(QualityName::Default), 64, 64, p, 5);
  EXPECT_EQ(play(r, 7), (std::vector<int>{0, 1, 2, 3, 4, 3, 2}));
  r.input(key(1, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{1}));  // the step the next frame would show
  r.input(key(2, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 4), (std::vector<int>{0, 1, 2, 3})) << "down to the first step, then up";
  r.input(key(3, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 7), (std::vector<int>{4}));
  r.input(key(4, proto::TimeKey::PlayPause), Clock::now());
  EXPECT_EQ(play(r, 3), (std::vector<int>{3, 2, 1})) << "paused at the top: on down";
}

TEST(Refinement, TimeKeysDoNothingWithoutASeries) {
  Refinement r = make();
  r.issued(*r.next(Clock::now()));
  r.input(key(1, proto::TimeKey::Forward), Clock::now());
  EXPECT_FALSE(r.next(Clock::now()));
}

}  // namespace
}  // namespace tessera::master
