#include "master/interaction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/scene.h"

namespace tessera::master {
namespace {

Camera camera() { return Camera{}; }  // eye (0,0,2.5) looking at the origin, y up

TEST(Interaction, OrbitKeepsTheDistanceAndZoomScalesIt) {
  proto::Input in;
  in.orbit_dx = 90;
  Camera c = applyInput(camera(), in);
  EXPECT_NEAR(length(c.eye - c.target), 2.5, 1e-9);
  EXPECT_NEAR(c.eye.z, 0, 1e-9) << "a quarter turn about up";
  in = {};
  in.zoom = 0.5;
  EXPECT_NEAR(length(applyInput(camera(), in).eye), 1.25, 1e-9);
}

TEST(Interaction, ZoomIsClampedAndTiltKeepsTheCameraValid) {
  proto::Input in;
  in.zoom = 100;
  EXPECT_NEAR(length(applyInput(camera(), in).eye), 12.5, 1e-9);
  in = {};
  in.orbit_dy = 90;  // onto the pole: whatever is kept, the camera stays valid
  Camera c = applyInput(camera(), in);
  EXPECT_NO_THROW(c.validate());
  EXPECT_NEAR(length(c.eye - c.target), 2.5, 1e-9);
}

// Zooming on and on stops at the scene file's distance limits, and the camera still answers:
// far out, the view direction once overflowed and every later input threw.
TEST(Interaction, ZoomStopsAtTheDistanceLimitsAndStillAnswers) {
  for (double step : {5.0, 0.2}) {
    Camera c = camera();
    if (step > 1) c.eye = {0, 0, 220000};  // 220000 * (1e6 / 220000) rounds to just past 1e6
    proto::Input in;
    in.zoom = step;
    for (int i = 0; i < 1000; ++i) c = applyInput(c, in);
    const double limit = step > 1 ? kMaxCameraDistance : kMinCameraDistance;
    EXPECT_NEAR(length(c.eye - c.target), limit, limit * 1e-9) << "zoom steps of " << step;
    EXPECT_GT(length(applyInput(c, in).eye - c.target), 0) << "still a camera";
    EXPECT_TRUE(cameraProblem(c).what.empty()) << cameraProblem(c).what;
    in.zoom = 1 / step;  // back the other way, and a turn
    in.orbit_dx = 30;
    const Camera back = applyInput(c, in);
    EXPECT_NEAR(length(back.eye - back.target), limit / step, limit / step * 1e-9);
    EXPECT_NO_THROW(back.validate());
  }
}

TEST(Interaction, BadValuesThrowInvalidArgument) {
  proto::Input in;
  in.zoom = 0;
  EXPECT_THROW(applyInput(camera(), in), std::invalid_argument);
  in.zoom = 1;
  in.orbit_dx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(applyInput(camera(), in), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::master

namespace tessera::master {
namespace {

TEST(Interaction, TheColourWindowIsSaidInTheVolumesValuesWithTheSceneKeyThatKeepsIt) {
  Scene scene;
  RawVolumeSpec file;
  file.has_range = true;
  file.range = {-1000, 3000};
  scene.volume = file;
  const std::string note = windowNote(scene, {0.25, 0.1});
  EXPECT_NE(note.find("values -200 to 200;"), std::string::npos) << note;
  EXPECT_NE(note.find("give the scene `window: {level: 0, width: 400}`"), std::string::npos) << note;
  EXPECT_NE(windowNote(scene, {}).find("as the scene gives it"), std::string::npos);
  scene.window = ValueWindow{0, 400};  // the scene's own window is not news
  EXPECT_NE(windowNote(scene, {0.25, 0.1}).find("as the scene gives it"), std::string::npos);
  scene.volume = GeneratorSpec{};  // values 0..1
  scene.window.reset();
  EXPECT_NE(windowNote(scene, {0.25, 0.5}).find("values 0 to 0.5; to keep it, give the scene `window: {level: 0.25, width: 0.5}`"),
            std::string::npos) << windowNote(scene, {0.25, 0.5});
}

}  // namespace
}  // namespace tessera::master
