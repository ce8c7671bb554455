// Numerical stress (docs/DESIGN.md): opacity near 0 over very many samples and near 1 in one
// sample, grazing rays, eye inside, scales 1e-6..1e6, tiny and odd image sizes,
// orthographic cameras, non-finite input. Output must be finite everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "renderer/volume/raycaster.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

using test::allFinite;
using test::options;

// Orthographic camera looking down -z through the box centre: the ray crosses length 1.
const Camera kDownZ{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 30, true, 1.0};

TransferFunction flat(double alpha, double r = 1, double g = 0.5, double b = 0.25) {
  return TransferFunction({{0, r, g, b, alpha}, {1, r, g, b, alpha}});
}

Quality custom(double step, bool reference) {
  Quality q = namedQuality(reference ? "reference" : "default");
  q.step = step;
  q.early_termination = 2.0;
  return q;
}

class TinyOpacity : public ::testing::TestWithParam<bool> {};

TEST_P(TinyOpacity, ManySamplesMatchTheClosedForm) {
  const bool reference = GetParam();
  // Per-sample opacity a = 1e-6 at step 1e-5: ~1e5 samples along the unit ray.
  const double step = 1e-5, a = 1e-6;
  const double alpha = -std::expm1(std::log1p(-a) * (kL0 / step));  // inverse of the correction
  const Raycaster rc(test::constant({8, 8, 8}, 0.5f), flat(alpha));
  RenderOptions opt;
  opt.quality = custom(step, reference);
  RenderStats st;
  const ImageF img = rc.render(kDownZ, 1, 1, Brick{{0, 0, 0}, {8, 8, 8}}, opt, &st);
  const double n = (double)st.samples;
  ASSERT_NEAR(n, 1e5, 1.0);
  const double expected = -std::expm1(n * std::log1p(-a));  // 1 - (1 - a)^n ~ 0.0952
  // Reference: double accumulation (error ~1e5 * 1e-16) stored as float (half ulp at 0.1 is
  // 3.7e-9). Fast: float; each of the
  // 1e5 additions of ~1e-6 to A ~ 0.05..0.1 rounds by <= 2^-28 absolute, so <= 4e-4 total
  // in the worst case (random rounding gives far less); the table's float a adds 1e-7 relative.
  const double tol = reference ? 1e-8 : 4e-4;
  RecordProperty("abs_error", std::to_string(std::abs(img.px[3] - expected)));
  EXPECT_NEAR(img.px[3], expected, tol);
  EXPECT_NEAR(img.px[0], expected * 1.0, tol);  // premultiplied colour = A * c for constant c
  EXPECT_NEAR(img.px[1], expected * 0.5, tol);
  EXPECT_NEAR(img.px[2], expected * 0.25, tol);
}

INSTANTIATE_TEST_SUITE_P(Paths, TinyOpacity, ::testing::Values(false, true));

TEST(Opaque, OneSampleSaturates) {
  const Raycaster rc(test::constant({8, 8, 8}, 0.5f), flat(1.0, 0.2, 0.4, 0.6));
  for (const char* q : {"default", "reference"}) {
    RenderStats st;
    const ImageF img = rc.render(kDownZ, 1, 1, Brick{{0, 0, 0}, {8, 8, 8}}, options(q), &st);
    // alpha 1 corrects to a = 1 for any step: the first sample is everything.
    EXPECT_EQ(img.px[3], 1.0f) << q;
    EXPECT_FLOAT_EQ(img.px[0], 0.2f) << q;
    EXPECT_FLOAT_EQ(img.px[1], 0.4f) << q;
    EXPECT_FLOAT_EQ(img.px[2], 0.6f) << q;
    if (std::string(q) == "default") {
      EXPECT_EQ(st.samples, 1u);  // early termination right after it
      EXPECT_EQ(st.samples_terminated, 255u);
    }
  }
}

// Fast vs reference on awkward views; PSNR >= 40 dB is the DESIGN accuracy contract.
void expectNearReference(const std::shared_ptr<const Volume>& vol, const Camera& cam, int w, int h,
                         const std::string& name) {
  const Raycaster rc(vol, test::defaultTf());
  const ImageF fast = rc.render(cam, w, h, wholeVolume(*vol), options("default"));
  const ImageF ref = rc.render(cam, w, h, wholeVolume(*vol), options("reference"));
  ASSERT_TRUE(allFinite(fast)) << name;
  ASSERT_TRUE(allFinite(ref)) << name;
  ASSERT_GT(activeRegion(ref).area(), 20) << name << ": the view must see something";
  EXPECT_GE(compare(fast, ref).psnr, 40.0) << name << " see " << test::dumpImages(name, ref, fast);
}

TEST(Views, GrazingAlongFacesAndEdges) {
  auto vol = test::generated("marschner-lobb", 24);
  // Looking straight down the box edge x = y = 0.5 and along the face x = -0.5.
  expectNearReference(vol, Camera{{0.5, 0.5, 3}, {0.5, 0.5, 0}, {0, 1, 0}, 20, false, 1}, 33, 31, "grazing_edge");
  expectNearReference(vol, Camera{{-0.5, 0, 3}, {-0.5, 0, 0}, {0, 1, 0}, 1, true, 1.0}, 17, 40, "grazing_face_ortho");
}

TEST(Views, EyeInsideTheVolume) {
  expectNearReference(test::generated("noise-cloud", 32), Camera{{0.05, 0.02, 0.1}, {0.3, -0.2, -1}, {0, 1, 0}, 70, false, 1},
                      40, 32, "eye_inside");
}

TEST(Views, Orthographic) {
  expectNearReference(test::generated("hollow-shell", 32), Camera{{1.5, 1.0, 2.0}, {0, 0, 0}, {0, 1, 0}, 30, true, 1.3},
                      40, 40, "orthographic");
}

TEST(Scale, SpacingScaledBy1e6And1eMinus6GivesTheSameImage) {
  // The box is normalised (largest extent 1), so only rounding in halfExtent may differ.
  const Camera cam = test::defaultCamera();
  ImageF base;
  for (double s : {1.0, 1e-6, 1e6}) {
    auto vol = test::generated("hollow-shell", 24, {1 * s, 1.5 * s, 0.75 * s});
    const Raycaster rc(vol, test::defaultTf());
    const ImageF img = rc.render(cam, 40, 40, wholeVolume(*vol), options("default"));
    ASSERT_TRUE(allFinite(img));
    if (s == 1.0) {
      base = img;
      ASSERT_GT(activeRegion(base).area(), 100);
    } else {
      EXPECT_LE(compare(img, base).max_abs, 1e-5) << "spacing scale " << s;
    }
  }
}

TEST(Sizes, OnePixelEqualsTheCentreOfAThreeByThreeImage) {
  auto vol = test::generated("hollow-shell", 32);
  const Raycaster rc(vol, test::defaultTf());
  const ImageF one = rc.render(test::defaultCamera(), 1, 1, wholeVolume(*vol), options("default"));
  const ImageF nine = rc.render(test::defaultCamera(), 3, 3, wholeVolume(*vol), options("default"));
  ASSERT_TRUE(allFinite(one));
  EXPECT_GT(one.px[3], 0.5f);  // the ray through the centre crosses the bright core
  for (int c = 0; c < 4; ++c) EXPECT_EQ(one.px[c], nine.at(1, 1)[c]);
}

TEST(Sizes, LargeOddImageWithTinyVolume) {
  auto vol = test::generated("noise-cloud", 8);
  const Raycaster rc(vol, test::defaultTf());
  Rect active;
  RenderStats st;
  const ImageF img = rc.render(test::defaultCamera(), 1023, 769, wholeVolume(*vol), options("fast"), &st, &active);
  ASSERT_EQ(img.width, 1023);
  ASSERT_EQ(img.height, 769);
  EXPECT_TRUE(allFinite(img));
  EXPECT_EQ(active, activeRegion(img));
  EXPECT_GT(active.area(), 1000);
  EXPECT_GT(st.samples, 0u);
}

TEST(Input, NonFiniteVolumeValuesAreRejected) {
  auto v = std::make_shared<Volume>(*test::constant({4, 4, 4}, 0.5f));
  v->values[37] = std::numeric_limits<float>::quiet_NaN();
  try {
    Raycaster rc(v, test::defaultTf());
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("37"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera::renderer
