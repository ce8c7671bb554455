#include "master/interaction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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
