// MaxIntensity's floor and mapping, value pixels merged by maxima in every wire format, and
// the scene's `blend` key.
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
  const Scene s = parseScene(base + "blend: maximum\n", ".");
  EXPECT_EQ(s.blend, Blend::Maximum);
  EXPECT_EQ(parseScene(sceneYaml(s), ".").blend, Blend::Maximum);
  auto error = [&](const std::string& text) {
    try {
      parseScene(text, ".", "s.yaml");
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error(base + "blend: mip\n").find("s.yaml: blend: 'mip': expected composite or maximum"), std::string::npos)
      << error(base + "blend: mip\n");
  EXPECT_NE(error(base + "blend: maximum\nshading: true\n").find("leave `shading` out"), std::string::npos);
  const std::string mesh = base + "mesh: {isosurface: {of: volume, level: 0.5}}\nblend: maximum\n";
  EXPECT_NE(error(mesh).find("s.yaml: blend: blends volume samples"), std::string::npos) << error(mesh);
}

}  // namespace
}  // namespace tessera
