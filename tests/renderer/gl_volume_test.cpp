// GLSL (OSMesa) volume backend against the CPU ray caster and the reference, skipping
// on/off, bricks composited vs whole, and a context that cannot be created.
#include "renderer/volume/gl_volume.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "common/bricks.h"
#include "renderer/gl/gl_context.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

using test::defaultCamera;
using test::defaultTf;
using test::generated;
using test::options;

constexpr int kW = 64, kH = 48;

// Max abs difference after rgba8 quantization, in 1/255 units.
int maxDiff8(const ImageF& a, const ImageF& b) {
  const Image8 qa = toRGBA8(a), qb = toRGBA8(b);
  int m = 0;
  for (size_t i = 0; i < qa.px.size(); ++i) m = std::max(m, std::abs((int)qa.px[i] - (int)qb.px[i]));
  return m;
}

TfPoint pt(double s, double r, double g, double b, double a) { return TfPoint{s, r, g, b, a}; }

struct Case {
  const char* generator;
  TransferFunction tf;
  Camera cam;
};

std::vector<Case> cases() {
  Camera oblique;
  oblique.eye = {1.6, 0.8, 1.6};
  Camera top;
  top.eye = {0.3, 2.2, 0.6};
  return {
      {"hollow-shell", defaultTf(), defaultCamera()},
      {"marschner-lobb",
       TransferFunction({pt(0, 0, 0, 0, 0), pt(0.4, 0.1, 0.3, 0.9, 0), pt(0.5, 0.3, 0.7, 1, 0.3),
                         pt(0.6, 1, 0.9, 0.6, 0), pt(1, 0, 0, 0, 0)}),
       top},
      {"noise-cloud",
       TransferFunction({pt(0, 0.6, 0.7, 0.9, 0), pt(0.03, 0.6, 0.7, 0.9, 0), pt(0.1, 0.6, 0.7, 0.9, 0.01),
                         pt(0.4, 0.9, 0.9, 1, 0.04), pt(1, 1, 1, 1, 0.15)}),
       oblique},
  };
}

TEST(GlVolume, MatchesCpuBackendAndReference) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.generator);
    auto vol = generated(c.generator, 40);
    const Raycaster cpu(vol, c.tf);
    const GlVolumeRenderer glr(vol, c.tf);
    const Brick all = wholeVolume(*vol);
    RenderStats gs, cs;
    Rect ga, ca;
    const ImageF g = glr.render(c.cam, kW, kH, all, options("default"), &gs, &ga);
    const ImageF f = cpu.render(c.cam, kW, kH, all, options("default"), &cs, &ca);
    const ImageF ref = cpu.render(c.cam, kW, kH, all, options("reference"));
    const ImageError e_cpu = compare(g, f), e_ref = compare(g, ref);
    std::printf("[%s] gl vs cpu: max_abs=%.3g (rgba8 %d/255) rmse=%.3g; gl vs reference: psnr=%.2f dB "
                "(cpu %.2f dB); samples gl=%llu cpu=%llu\n",
                c.generator, e_cpu.max_abs, maxDiff8(g, f), e_cpu.rmse, e_ref.psnr, compare(f, ref).psnr,
                (unsigned long long)gs.samples, (unsigned long long)cs.samples);
    ASSERT_TRUE(test::allFinite(g));
    // 1/255: float32 GLSL (texture-unit trilinear) vs the CPU's float path, after rgba8 rounding.
    EXPECT_LE(maxDiff8(g, f), 1) << test::dumpImages(std::string("gl_vs_cpu_") + c.generator, f, g);
    // In float the two differ only by texture-unit vs CPU rounding (measured ~2e-6).
    EXPECT_LE(e_cpu.max_abs, 1e-4);
    // docs/DESIGN.md accuracy contract for default quality.
    EXPECT_GE(e_ref.psnr, 40.0);
    EXPECT_EQ(ga, ca) << "active regions differ";
    // Same span per pixel: taken + leapt + terminated covers every sample of the grid.
    EXPECT_EQ(gs.samples + gs.samples_skipped + gs.samples_terminated,
              cs.samples + cs.samples_skipped + cs.samples_terminated);
  }
}

// A slice far thinner than the step is sampled across as the CPU ray caster samples it.
TEST(GlVolume, ASliceIsSampledAsTheCpuSamplesIt) {
  auto vol = test::slice();
  const Raycaster cpu(vol, test::opaqueTf());
  const GlVolumeRenderer glr(vol, test::opaqueTf());
  const ImageF g = glr.render(defaultCamera(), kW, kH, wholeVolume(*vol), options("default"));
  const ImageF f = cpu.render(defaultCamera(), kW, kH, wholeVolume(*vol), options("default"));
  ASSERT_GT(activeRegion(g).area(), 1000) << "the slice was not sampled";
  EXPECT_LE(maxDiff8(g, f), 1) << test::dumpImages("gl_vs_cpu_slice", f, g);
}

TEST(GlVolume, SkippingChangesNoBit) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.generator);
    auto vol = generated(c.generator, 48);
    const GlVolumeRenderer glr(vol, c.tf);
    RenderOptions on = options("default"), off = on;
    off.quality.skip_empty = false;
    RenderStats son, soff;
    const ImageF a = glr.render(c.cam, kW, kH, wholeVolume(*vol), on, &son);
    const ImageF b = glr.render(c.cam, kW, kH, wholeVolume(*vol), off, &soff);
    EXPECT_TRUE(a == b) << "max abs " << compare(a, b).max_abs;
    EXPECT_EQ(soff.samples_skipped, 0u);
    if (std::string(c.generator) != "marschner-lobb") {
      EXPECT_GT(son.samples_skipped, 0u) << "nothing was leapt over";
    }
  }
}

TEST(GlVolume, BricksCompositeToWhole) {
  const Case c = cases()[0];
  auto vol = generated(c.generator, 40, {1, 1.5, 0.75});
  const GlVolumeRenderer glr(vol, c.tf);
  const RenderOptions opt = options("default");
  for (const Camera& cam : {c.cam, cases()[2].cam}) {
    const ImageF whole = glr.render(cam, kW, kH, wholeVolume(*vol), opt);
    for (int n : {2, 5}) {
      const BrickTree tree = splitBricks(*vol, n, &c.tf);
      ImageF out(kW, kH);
      for (int leaf : tree.visibilityOrder(*vol, cam)) {
        Rect act;
        const ImageF part = glr.render(cam, kW, kH, tree.bricks[leaf], opt, nullptr, &act);
        if (!act.empty()) compositeOver(out, part, act);
      }
      // 1/255: the farm contract for any brick split (rgba8).
      EXPECT_LE(maxDiff8(out, whole), 1) << n << " bricks; " << test::dumpImages("gl_bricks", whole, out);
    }
  }
}

TEST(GlVolume, EdgeCasesStayFinite) {
  auto vol = generated("hollow-shell", 33);
  const GlVolumeRenderer glr(vol, defaultTf());
  const Raycaster cpu(vol, defaultTf());
  Camera inside;
  inside.eye = {0.05, 0.1, 0.2};
  Camera axis;  // rays parallel to an axis through the box
  axis.eye = {0, 0, 2.5};
  axis.orthographic = true;
  axis.height = 1.2;
  for (const Camera& cam : {inside, axis}) {
    for (auto [w, h] : {std::pair{1, 1}, std::pair{17, 9}}) {
      const ImageF g = glr.render(cam, w, h, wholeVolume(*vol), options("default"));
      const ImageF f = cpu.render(cam, w, h, wholeVolume(*vol), options("default"));
      ASSERT_TRUE(test::allFinite(g));
      EXPECT_LE(maxDiff8(g, f), 1) << w << "x" << h;
    }
  }
}

TEST(GlVolume, ReferenceQualityIsTheCpuReference) {
  auto vol = generated("hollow-shell", 32);
  const GlVolumeRenderer glr(vol, defaultTf());
  const Raycaster cpu(vol, defaultTf());
  const ImageF g = glr.render(defaultCamera(), 16, 12, wholeVolume(*vol), options("reference"));
  const ImageF f = cpu.render(defaultCamera(), 16, 12, wholeVolume(*vol), options("reference"));
  EXPECT_TRUE(g == f);
}

TEST(GlVolume, ImpossibleContextIsOneClearLine) {
  try {
    gl::GlContext ctx("test", 9, 9);
    FAIL() << "OSMesa created a 9.9 context";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("9.9 core profile"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(GlVolume, RejectsBadInput) {
  auto vol = generated("hollow-shell", 16);
  const GlVolumeRenderer glr(vol, defaultTf());
  EXPECT_THROW(glr.render(defaultCamera(), 0, 4, wholeVolume(*vol), options("default")), std::invalid_argument);
  EXPECT_THROW(glr.render(defaultCamera(), 4, 4, Brick{{0, 0, 0}, {17, 16, 16}}, options("default")),
               std::invalid_argument);
  auto bad = std::make_shared<Volume>(*vol);
  bad->values[5] = NAN;
  EXPECT_THROW(GlVolumeRenderer(bad, defaultTf()), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::renderer
