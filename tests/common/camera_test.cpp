// Ray generation per DESIGN.md, projection as its inverse, and camera validation.
#include "common/camera.h"
#include "common/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
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

// Every corner of the box must land inside the image, a portrait one included (the fov is
// vertical: fitted to it alone, a tall image cut the box's sides).
TEST(FittedCamera, SeesTheWholeBoxWhateverTheImagesShape) {
  for (const char* image : {"[1024, 1024]", "[2048, 512]", "[512, 1024]", "[100, 1000]"}) {
    const Scene s = parseScene(
        std::string("volume: {generator: {name: hollow-shell, size: 16}, spacing: [1, 1, 2]}\nimage: ") + image + "\n",
        ".", "s.yaml");
    const RayGenerator rays(s.camera, s.width, s.height);
    const Vec3 h = sceneHalfExtent(s);
    double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p{corner & 1 ? h.x : -h.x, corner & 2 ? h.y : -h.y, corner & 4 ? h.z : -h.z};
      double sx = 0, sy = 0;
      ASSERT_TRUE(rays.project(p, sx, sy)) << image;
      min_x = std::min(min_x, sx), max_x = std::max(max_x, sx), min_y = std::min(min_y, sy), max_y = std::max(max_y, sy);
    }
    EXPECT_GE(min_x, 0) << image;
    EXPECT_LE(max_x, s.width) << image;
    EXPECT_GE(min_y, 0) << image;
    EXPECT_LE(max_y, s.height) << image;
    // Not farther than needed: the bounding sphere fitted, this long box still fills over a
    // third of the narrower side (0.40-0.45 here).
    EXPECT_GT(std::max((max_x - min_x) / s.width, (max_y - min_y) / s.height), 0.35) << image;
  }
}
