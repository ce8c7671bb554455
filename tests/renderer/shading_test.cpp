// Gradient shading (renderer/volume/gradient.h): the lit colour against the formula on volumes
// whose gradient is known, the fast path against the double-precision reference, and the
// backends' refusal where shading is not implemented.
#include <gtest/gtest.h>

#include <cmath>

#include "renderer/volume/backend.h"
#include "renderer/volume/gradient.h"
#include "renderer/volume/kernels.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

// v = (ax * x + ay * y) / (ax + ay) / 15 on a 16^3 grid: a constant gradient in the x-y plane.
std::shared_ptr<const Volume> ramp(double ax, double ay, std::array<double, 3> spacing) {
  auto v = std::make_shared<Volume>();
  v->dims = {16, 16, 16};
  v->spacing = spacing;
  v->values.resize(v->voxelCount());
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) v->values[v->index(x, y, z)] = (float)((ax * x + ay * y) / (ax + ay) / 15);
  return v;
}

// One colour, one opacity over every value: a pixel's colour / alpha is the lit colour.
const TransferFunction kFlatTf({{0, 1, 0.5, 0.25, 0.05}, {1, 1, 0.5, 0.25, 0.05}});

Camera lookingDownZ() {
  Camera c;
  c.eye = {0, 0, 3};
  c.orthographic = true;
  c.height = 0.6;  // inside the box: every pixel sees the volume
  return c;
}

// The lit colour (rgb / alpha) of the image's centre pixel.
std::array<double, 3> litColour(const Volume& v, const Vec3& light, const char* quality) {
  Shading sh;
  sh.on = true;
  auto vol = std::make_shared<const Volume>(v);
  const ImageF img = Raycaster(vol, kFlatTf, sh, light).render(lookingDownZ(), 9, 9, wholeVolume(v), test::options(quality));
  const float* p = img.at(4, 4);
  EXPECT_GT(p[3], 0.1f);
  return {p[0] / p[3], p[1] / p[3], p[2] / p[3]};
}

std::array<double, 3> formula(double n_dot_l, double n_dot_h) {
  const Shading s{true};  // ambient 0.1, diffuse 0.7, specular 0.2, shininess 10
  const double c[3] = {1, 0.5, 0.25}, highlight = std::pow(n_dot_h, s.shininess);
  std::array<double, 3> out{};
  for (int i = 0; i < 3; ++i) out[i] = std::min(1.0, c[i] * (s.ambient + s.diffuse * n_dot_l) + s.specular * highlight);
  return out;
}

struct LitCase {
  const char* quality;
  double tolerance;  // reference: double rounding; default: float and the 16-bit gradients
};

class LitColour : public ::testing::TestWithParam<LitCase> {};

TEST_P(LitColour, MatchesTheFormula) {
  const auto [quality, tol] = GetParam();
  // Gradient along x, eye along +z. Headlight: N.L = N.H = 0, only ambient remains.
  const auto x_ramp = ramp(1, 0, {1, 1, 1});
  const auto headlit = litColour(*x_ramp, {0, 0, 0}, quality), want_head = formula(0, 0);
  // Light along x: N.L = 1, H halfway between x and z: N.H = cos 45 degrees.
  const auto sidelit = litColour(*x_ramp, {1, 0, 0}, quality), want_side = formula(1, std::sqrt(0.5));
  // Gradient (1, 1, 0) per voxel, but cells twice as wide in x: the world gradient is
  // (0.5, 1, 0) / cell_y, so N.L = 0.5 / sqrt(1.25) for a light along x (N.H = N.L / sqrt 2).
  const auto diag = litColour(*ramp(1, 1, {2, 1, 1}), {1, 0, 0}, quality);
  const double nl = 0.5 / std::sqrt(1.25);
  const auto want_diag = formula(nl, nl * std::sqrt(0.5));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(headlit[i], want_head[i], tol) << "channel " << i;
    EXPECT_NEAR(sidelit[i], want_side[i], tol) << "channel " << i;
    EXPECT_NEAR(diag[i], want_diag[i], tol) << "channel " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, LitColour,
                         ::testing::Values(LitCase{"reference", 1e-6}, LitCase{"default", 1e-3}),
                         [](const auto& tc) { return std::string(tc.param.quality); });

TEST(Shading, FlatRegionsAreLitAsFacingTheLight) {
  const auto flat = test::constant({8, 8, 8}, 0.5f);
  for (const char* q : {"reference", "default"}) {
    const auto lit = litColour(*flat, {0, 0, 0}, q), want = formula(1, 0);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(lit[i], want[i], 1e-5) << q << " channel " << i;
  }
}

// The fast path (float, 16-bit gradients, skipping, early termination) against the reference
// (double, exact gradients): the contract for default quality, 40 dB, on shaded scenes.
TEST(Shading, FastPathWithin40dBOfReference) {
  Shading sh;
  sh.on = true;
  sh.specular = 0.4;
  for (const char* gen : {"marschner-lobb", "hollow-shell", "head"}) {
    auto vol = test::generated(gen, 48, {1, 1.25, 1});
    const Raycaster lit(vol, test::defaultTf(), sh), unlit(vol, test::defaultTf());
    const Camera cam = Orbit{8, {0.3, 1, 0}}.at(test::defaultCamera(), 1);
    const ImageF ref = lit.render(cam, 96, 96, wholeVolume(*vol), test::options("reference"));
    const ImageF fast = lit.render(cam, 96, 96, wholeVolume(*vol), test::options("default"));
    const ImageF plain = unlit.render(cam, 96, 96, wholeVolume(*vol), test::options("reference"));
    ASSERT_TRUE(test::allFinite(fast));
    EXPECT_GE(compare(fast, ref).psnr, 40.0) << gen << test::dumpImages(std::string("shaded_") + gen, ref, fast);
    // Shading must show: the lit image is far from the unlit one.
    EXPECT_LT(compare(plain, ref).psnr, 30.0) << gen;
  }
}

TEST(Shading, GradientIsTheCentralDifferenceOfTheField) {
  // Away from the faces, interpolated G equals (s(u + e) - s(u - e)) / 2 of the trilinear field.
  auto vol = test::generated("noise-cloud", 12);
  for (const auto& u : {std::array<double, 3>{4.3, 5.7, 6.1}, std::array<double, 3>{2.5, 8.25, 3.9}}) {
    double g[3];
    sampleGradient(*vol, u[0], u[1], u[2], g);
    for (int a = 0; a < 3; ++a) {
      auto plus = u, minus = u;
      plus[a] += 1, minus[a] -= 1;
      const double d = (sampleTrilinear(*vol, plus[0], plus[1], plus[2]) - sampleTrilinear(*vol, minus[0], minus[1], minus[2])) / 2;
      EXPECT_NEAR(g[a], d, 1e-12) << "axis " << a;
    }
  }
}

TEST(Shading, OsmesaBackendRefusesItByName) {
  Shading sh;
  sh.on = true;
  try {
    makeVolumeBackend(BackendKind::Osmesa, test::generated("hollow-shell", 16), test::defaultTf(), sh);
    ADD_FAILURE() << "osmesa accepted shading";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("osmesa volume backend does not shade"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera::renderer
