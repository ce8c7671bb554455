// Ray generation per DESIGN.md, projection as its inverse, and camera validation.
#include "common/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace tessera;

namespace {
void expectVec(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}
}  // namespace

TEST(Camera, CentreRayIsTheViewDirection) {
  Camera c{{1, 2, 3}, {1, 2, -1}, {0, 1, 0}, 40, false, 1};
  RayGenerator g(c, 3, 5);
  Ray r = g.pixelRay(1, 2);
  expectVec(r.origin, c.eye);
  expectVec(r.dir, {0, 0, -1});
}

TEST(Camera, CornerRayFollowsTheFormula) {
  // fov 90 -> tan = 1; W=4, H=2 -> aspect 2; pixel (0,0): x = (0.25-1)*2 = -1.5, y = 0.5.
  Camera c{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90, false, 1};
  RayGenerator g(c, 4, 2);
  Ray r = g.pixelRay(0, 0);
  expectVec(r.dir, normalize({-1.5, 0.5, -1}));
  Ray br = g.pixelRay(3, 1);
  expectVec(br.dir, normalize({1.5, -0.5, -1}));
}

TEST(Camera, OrthographicRaysAreParallel) {
  Camera c{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30, true, 2};
  RayGenerator g(c, 4, 2);
  Ray r = g.pixelRay(0, 0);
  expectVec(r.dir, {0, 0, -1});
  // x = (0.25 - 1) * aspect 2 * half-height 1 = -1.5; y = 0.5 * 1.
  expectVec(r.origin, {-1.5, 0.5, 5});
}

TEST(Camera, ProjectInvertsRay) {
  for (bool ortho : {false, true}) {
    Camera c{{0.3, 0.6, 2.2}, {0, 0, 0}, {0, 1, 0}, 30, ortho, 1.5};
    RayGenerator g(c, 64, 48);
    Ray r = g.ray(10.25, 33.5);
    Vec3 p = r.origin + r.dir * 1.7;
    double sx, sy;
    ASSERT_TRUE(g.project(p, sx, sy));
    EXPECT_NEAR(sx, 10.25, 1e-9);
    EXPECT_NEAR(sy, 33.5, 1e-9);
  }
  Camera c;
  RayGenerator g(c, 8, 8);
  double sx, sy;
  EXPECT_FALSE(g.project({0, 0, 3}, sx, sy));  // behind the eye at z = 2.5
}

TEST(Camera, ValidateRejectsDegenerateCameras) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto bad = [](Camera c, const char* what) {
    try {
      c.validate();
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  bad(Camera{{1, 1, 1}, {1, 1, 1}, {0, 1, 0}, 30, false, 1}, "eye equals target");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 0, 5}, 30, false, 1}, "parallel");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 0, false, 1}, "fov");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 180, false, 1}, "fov");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, -5, false, 1}, "fov");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 30, true, 0}, "height");
  bad(Camera{{0, nan, 2}, {0, 0, 0}, {0, 1, 0}, 30, false, 1}, "finite");
  bad(Camera{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, nan, false, 1}, "finite");
  // Tiny and huge scales are still valid cameras.
  EXPECT_NO_THROW((Camera{{0, 0, 1e-6}, {0, 0, 0}, {0, 1e-6, 0}, 30, false, 1}.validate()));
  EXPECT_NO_THROW((Camera{{0, 0, 1e6}, {0, 0, 0}, {0, 1, 0}, 179, false, 1}.validate()));
  EXPECT_THROW(RayGenerator(Camera{}, 0, 4), std::invalid_argument);
}

TEST(Camera, Orbited) {
  Camera c{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 30, false, 1};
  Camera o = c.orbited({0, 5, 0}, 90);
  expectVec(o.eye, {2, 0, 0});
  expectVec(o.up, {0, 1, 0});
  Camera full = c.orbited({1, 1, 0}, 360);
  expectVec(full.eye, c.eye, 1e-12);
}
