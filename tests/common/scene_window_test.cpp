// The scene key `window`: the colour map laid over a span of the volume's own values, and its
// conversion to the fraction of the mapped range each frame carries.
#include <gtest/gtest.h>

#include <string>

#include "common/scene.h"
#include "tests/common/scene_errors.h"

namespace tessera {
namespace {

// `window` lays the colour map over a span of the values, in the volume's units.
TEST(Scene, AWindowIsInTheVolumesValues) {
  const std::string gen = "volume: {generator: {name: hollow-shell, size: 16, seed: 1}}\n";
  const Scene s = parseScene(gen + "window: {level: 0.6, width: 0.4}\n", ".", "s.yaml");
  ASSERT_TRUE(s.window);
  EXPECT_EQ(*s.window, (ValueWindow{0.6, 0.4}));
  EXPECT_EQ(colorWindow(s), (ColorWindow{0.6, 0.4}));  // a generated volume's values run 0..1
  const ColorWindow hu = colorWindow(s, {-1000, 3000});
  EXPECT_DOUBLE_EQ(hu.center, (0.6 + 1000) / 4000);
  EXPECT_DOUBLE_EQ(hu.width, 0.4 / 4000);
  EXPECT_EQ(colorWindow(parseScene(gen, ".", "s.yaml")), ColorWindow{});
  // Far beside the values, a window is held within what a frame may carry (the same end colour).
  const Scene far = parseScene(gen + "window: {level: 1e12, width: 1e9}\n", ".", "s.yaml");
  EXPECT_EQ(colorWindow(far), (ColorWindow{1e6, 1e6}));
  // Wider than a frame carries yet over the values: they keep their place on the map (0 at 1/6).
  const ColorWindow wide = colorWindow(parseScene(gen + "window: {level: 1e12, width: 3e12}\n", ".", "s.yaml"));
  EXPECT_EQ(wide.width, 1e6);
  EXPECT_NEAR(0.5 - wide.center / wide.width, 1.0 / 6, 1e-12);
  // A constant volume's value c is mapped with c .. c + 1, as the master maps it.
  EXPECT_EQ(colorWindow(s, {7, 7}), (ColorWindow{0.6 - 7, 0.4}));
  const Scene thin = parseScene(gen + "window: {level: 0, width: 1e-10}\n", ".", "s.yaml");
  EXPECT_EQ(colorWindow(thin, {0, 1e300}).width, 1e-300) << "a width of 0 would be refused by every stage";
  EXPECT_EQ(parseScene(sceneYaml(s), ".", "t.yaml").window, s.window) << sceneYaml(s);
  // The master sends it with each frame: stages need not agree on it.
  EXPECT_EQ(sceneIdentity(s), sceneIdentity(parseScene(gen, ".", "s.yaml")));
  EXPECT_ERROR(gen + "window: {level: 0.5, width: 0}\n", "window.width: 0: expected a positive width");
  EXPECT_ERROR(gen + "window: {level: 0.5}\n", "window: expected {level: L, width: W}");
  EXPECT_ERROR(gen + "window: {level: 0.5, width: 1, gamma: 2}\n", "window.gamma: unknown key");
  EXPECT_ERROR(gen + "window: [0.5, 1]\n", "window: expected {level: L, width: W}");
}

}  // namespace
}  // namespace tessera
