// MaxIntensity's floor and mapping (the minimum projection's by the mirrored map), value
// pixels merged by maxima in every wire format, and the scene's `blend` key.
#include <gtest/gtest.h>

#include <cmath>

#include "common/max_intensity.h"
#include "common/scene.h"
#include "common/wire/pixels.h"

namespace tessera {
namespace {

TEST(MaxIntensityMap, FloorIsWhereOpacityStarts) {
  EXPECT_EQ(MaxIntensity(TransferFunction({{0, 0, 0, 0, 0}, {0.25, 1, 0, 0, 0}, {1, 1, 1, 1, 0.5}})).floor(), 0.25);
  EXPECT_EQ(MaxIntensity(TransferFunction({{0, 0, 0, 0, 0}, {0.25, 1, 0, 0, 0}, {1, 1, 1, 1, 0.5}})).floorQ(),
            (uint32_t)std::floor(0.25 * 65535));
  EXPECT_EQ(MaxIntensity(TransferFunction({{0.5, 0, 0, 0, 0.1}, {1, 1, 1, 1, 0.5}})).floor(), 0);  // opaque from the start
  EXPECT_EQ(MaxIntensity(TransferFunction({{0, 0, 0, 0, 0}, {1, 1, 1, 1, 0}})).floorQ(), UINT32_MAX);
}

TEST(MaxIntensityMap, MapsTheValueWithOpacityScaledToOne) {
  // Opacity 0 at 0.2, 0.04 at 1 (the largest): at 0.6 it is 0.02 of 0.04, shown as 0.5.
  const MaxIntensity m(TransferFunction({{0, 0, 0, 0, 0}, {0.2, 0, 0, 1, 0}, {1, 1, 0, 0, 0.04}}));
  float px[8] = {0.6f, 0, 0, 1, 0, 0, 0, 0};  // a value pixel, and a transparent one
  m.map(px, 2);
  EXPECT_NEAR(px[3], 0.5, 1e-6);
  EXPECT_NEAR(px[0], 0.5 * 0.5, 1e-6);  // red halfway, premultiplied
  EXPECT_NEAR(px[2], 0.5 * 0.5, 1e-6);
  for (int c = 4; c < 8; ++c) EXPECT_EQ(px[c], 0.0f);  // transparent stays transparent
}

// The minimum projection's pixel holds 1 - m (m the ray's smallest value) and is mapped by the
// colour map mirrored: it shows the map's colour at m, and its floor keeps every m up to where
// the map's opacity ends.
TEST(MaxIntensityMap, TheMinimumProjectionMapsComplementsByTheMirroredMap) {
  const TransferFunction tf({{0, 0, 0, 1, 0.04}, {0.3, 0.5, 0.5, 0.5, 0.02}, {0.6, 1, 0, 0, 0}, {1, 1, 1, 1, 0}});
  const TransferFunction m = mirrored(tf);
  for (double s : {0.0, 0.1, 0.3, 0.45, 0.6, 0.77, 1.0})
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(m.eval(s)[c], tf.eval(1 - s)[c], 1e-12) << s << " " << c;
  ASSERT_EQ(mirrored(m).points().size(), tf.points().size());
  for (size_t i = 0; i < tf.points().size(); ++i) {
    TfPoint a = mirrored(m).points()[i];
    const TfPoint b = tf.points()[i];
    EXPECT_NEAR(a.s, b.s, 1e-15);  // 1 - (1 - s) rounds
    a.s = b.s;
    EXPECT_EQ(a, b);
  }
  const MaxIntensity minimum(tf, true);
  EXPECT_NEAR(minimum.floor(), 1 - 0.6, 1e-12);  // m above 0.6 shows nothing
  float px[8] = {(float)(1 - 0.3), 0, 0, 1, 0, 0, 0, 0};  // m = 0.3, and a transparent pixel
  minimum.map(px, 2);
  EXPECT_NEAR(px[3], 0.5, 1e-6);  // 0.02 of the largest 0.04
  EXPECT_NEAR(px[0], 0.5 * 0.5, 1e-6);
  EXPECT_NEAR(px[2], 0.5 * 0.5, 1e-6);
  for (int c = 4; c < 8; ++c) EXPECT_EQ(px[c], 0.0f);
  // A step keeps its sides: below 0.5 black, from 0.5 on white.
  const TransferFunction step({{0, 0, 0, 0, 1}, {0.5, 0, 0, 0, 1}, {0.5, 1, 1, 1, 1}, {1, 1, 1, 1, 1}});
  EXPECT_EQ(mirrored(step).eval(1 - 0.25)[0], 0.0);
  EXPECT_EQ(mirrored(step).eval(1 - 0.75)[0], 1.0);
}

TEST(MaxIntensityMap, ValuePixelsMergeByTheirMaximaInEveryFormat) {
  ImageF a(4, 1), b(4, 1);
  const float sa[4] = {0.25f, 0.75f, 0, 0.5f}, sb[4] = {0.5f, 0.125f, 0.875f, 0};
  for (int x = 0; x < 4; ++x) {
    if (sa[x] > 0) a.at(x, 0)[0] = sa[x], a.at(x, 0)[3] = 1;
    if (sb[x] > 0) b.at(x, 0)[0] = sb[x], b.at(x, 0)[3] = 1;
  }
  for (auto f : {proto::PixelFormat::RGBA8, proto::PixelFormat::RGBA16F, proto::PixelFormat::RGBA32F}) {
    ImageF dst = a;
    const Rect r{0, 0, 4, 1};
    compositeMaximum(dst, r, packPixels(b, r, f), r, f);
    for (int x = 0; x < 4; ++x) {
      EXPECT_NEAR(dst.at(x, 0)[0], std::max(sa[x], sb[x]), f == proto::PixelFormat::RGBA8 ? 0.5 / 255 + 1e-6 : 0) << x;
      EXPECT_EQ(dst.at(x, 0)[3], 1.0f) << x;  // one of them showed
    }
  }
  ImageF dst = a;
  compositeMaximum(dst, b, {0, 0, 4, 1});
  for (int x = 0; x < 4; ++x) EXPECT_EQ(dst.at(x, 0)[0], std::max(sa[x], sb[x]));
}

TEST(SceneBlend, ParsesWritesAndRefuses) {
  const std::string base = "volume: {generator: {name: hollow-shell, size: 16}}\n";
  EXPECT_EQ(parseScene(base, ".").blend, Blend::Composite);
  for (Blend b : {Blend::Maximum, Blend::Minimum}) {
    const Scene s = parseScene(base + "blend: " + blendName(b) + "\n", ".");
    EXPECT_EQ(s.blend, b);
    EXPECT_EQ(parseScene(sceneYaml(s), ".").blend, b);
  }
  auto error = [&](const std::string& text) {
    try {
      parseScene(text, ".", "s.yaml");
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error(base + "blend: mip\n").find("s.yaml: blend: 'mip': expected composite, maximum or minimum"),
            std::string::npos)
      << error(base + "blend: mip\n");
  EXPECT_NE(error(base + "blend: maximum\nshading: true\n").find("leave `shading` out"), std::string::npos);
  EXPECT_NE(error(base + "blend: minimum\nshading: true\n").find("minimum shows each ray's smallest value"),
            std::string::npos)
      << error(base + "blend: minimum\nshading: true\n");
  const std::string mesh = base + "mesh: {isosurface: {of: volume, level: 0.5}}\nblend: maximum\n";
  EXPECT_NE(error(mesh).find("s.yaml: blend: blends volume samples"), std::string::npos) << error(mesh);
}

}  // namespace
}  // namespace tessera
