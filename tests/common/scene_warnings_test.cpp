// Warnings about a scene's volume: they name the scene and the key, and say what to do.
#include "common/scene_warnings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "common/transfer_function.h"
#include "tests/common/raw_spec.h"

namespace tessera {
namespace {

Volume shape(std::array<int, 3> dims, std::array<double, 3> spacing = {1, 1, 1}) {
  Volume v;
  v.dims = dims;
  v.spacing = spacing;
  v.data_range = v.mapped_range = {0, 1000};
  return v;
}

// A raw file's scene (the file need not exist: nothing is read) with the default colour map.
Scene sceneOf(bool has_range, std::array<double, 2> range = {0, 0}) {
  Scene s = defaultScene();
  s.path = "data/slice.yaml";
  s.volume = test::rawSpec("a.raw", {32, 32, 32}, VoxelType::UInt16, {1, 1, 1}, has_range, range);
  s.tf = transferFunctionPreset("cool-to-warm");
  return s;
}

TEST(VolumeWarnings, ARangeThatMissesTheDataNamesTheSceneAndTheKey) {
  const Scene s = sceneOf(true, {5000, 6000});
  Volume v = shape({32, 32, 32});
  v.mapped_range = {5000, 6000};
  const auto w = volumeWarnings(s, v);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("data/slice.yaml: volume.range: range [5000, 6000] lies above every value", 0), 0u) << w[0];
  // Without `range` in the scene, a constant volume is the volume's fault, not the key's.
  Volume flat = shape({32, 32, 32});
  flat.data_range = {7, 7};
  flat.mapped_range = {7, 8};
  const auto c = volumeWarnings(sceneOf(false), flat);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].rfind("data/slice.yaml: volume: every voxel has the value 7", 0), 0u) << c[0];
}

// A minimum projection of a whole volume shows the background around the object: said, with
// the crop that helps; a cropped one is not warned about.
TEST(VolumeWarnings, AMinimumProjectionOfTheWholeVolumeAdvisesACrop) {
  Scene s = sceneOf(true, {0, 1000});
  s.blend = Blend::Minimum;
  const auto w = volumeWarnings(s, shape({32, 32, 32}));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("data/slice.yaml: blend: minimum over the whole volume", 0), 0u) << w[0];
  EXPECT_NE(w[0].find("crop: {z: [0.4, 0.6]}"), std::string::npos) << w[0];
  s.crop.axes[2] = {0.4, 0.6};
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty());
  s.blend = Blend::Maximum;
  s.crop = Crop{};
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty());
}

// A `window` beside all of the data's values (a CT window on an MRI's 0..1000, say) is said;
// one that meets them is not.
TEST(VolumeWarnings, AWindowBesideEveryValueIsSaid) {
  Scene s = sceneOf(true, {0, 1000});
  s.window = ValueWindow{2000, 400};
  const auto w = volumeWarnings(s, shape({32, 32, 32}));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0], "data/slice.yaml: window: level 2000, width 400 spans 1800 .. 2200, none of the volume's values 0 .. 1000: "
                  "every voxel takes the colour map's bottom end");
  s.window = ValueWindow{-300, 400};
  ASSERT_EQ(volumeWarnings(s, shape({32, 32, 32})).size(), 1u);
  s.window = ValueWindow{1100, 400};  // 900 .. 1300 meets the values
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty());
  // The voxels are clamped to the range first: data up to 4000 is no help past a range of 0 .. 1000.
  Volume wider = shape({32, 32, 32});
  wider.data_range = {0, 4000};
  s.window = ValueWindow{2000, 400};
  const auto c = volumeWarnings(s, wider);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0], "data/slice.yaml: window: level 2000, width 400 spans 1800 .. 2200, none of the volume's values 0 .. 1000 "
                  "(as volume.range clamps them): every voxel takes the colour map's bottom end; widen volume.range or "
                  "leave it out");
  // Narrower than the casters resolve the mapped range.
  s.window = ValueWindow{500, 2};
  const auto n = volumeWarnings(s, shape({32, 32, 32}));
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0], "data/slice.yaml: window: width 2 is under 1/256 of the mapped range 0 .. 1000: the colour map shows in "
                  "coarse steps; give volume.range closer to the window");
}

// An opacity peak narrower than two of the fast kernels' table steps may vanish (a 0.0002-wide
// isovalue spike did, silently: found by review); the reference evaluates the map exactly.
TEST(VolumeWarnings, AnOpacityPeakTheTableMayMissIsSaid) {
  Scene s = sceneOf(true, {0, 1000});
  s.tf = TransferFunction({{0, 0, 0, 0, 0}, {0.4999, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {0.5001, 1, 1, 1, 0}, {1, 0, 0, 0, 0}});
  const auto w = volumeWarnings(s, shape({32, 32, 32}));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("data/slice.yaml: transfer_function: the opacity peak at 0.5 of the map is 0.0002 wide, under two "
                       "steps (0.000488) of the table", 0), 0u) << w[0];
  s.tf = TransferFunction({{0, 0, 0, 0, 0}, {0.4999, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {0.5001, 1, 1, 1, 1}, {0.5002, 1, 1, 1, 0},
                           {1, 0, 0, 0, 0}});  // a plateau
  const auto plateau = volumeWarnings(s, shape({32, 32, 32}));
  ASSERT_EQ(plateau.size(), 1u);
  EXPECT_NE(plateau[0].find("the opacity peak at 0.5 of the map is 0.0003 wide"), std::string::npos) << plateau[0];
  s.quality.reference = true;
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty()) << "the reference evaluates the map exactly";
  s.quality.reference = false;
  // Wide enough: 0.001 spans four steps. A window narrows the steps with the map: no warning.
  s.tf = TransferFunction({{0, 0, 0, 0, 0}, {0.4995, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {0.5005, 1, 1, 1, 0}, {1, 0, 0, 0, 0}});
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty());
  s.tf = TransferFunction({{0, 0, 0, 0, 0}, {0.4, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {0.6, 1, 1, 1, 0}, {1, 0, 0, 0, 0}});
  s.window = ValueWindow{500, 5};  // the peak 1 value wide in a map over 0 .. 1000
  const auto n = volumeWarnings(s, shape({32, 32, 32}));
  for (const auto& x : n) EXPECT_EQ(x.find("opacity peak"), std::string::npos) << x;
  // A map constant (colour too) beside the spike gives the table to the spike alone: no warning.
  s.window.reset();
  s.tf = TransferFunction({{0, 1, 1, 1, 0}, {0.4999, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {0.5001, 1, 1, 1, 0}, {1, 1, 1, 1, 0}});
  EXPECT_TRUE(volumeWarnings(s, shape({32, 32, 32})).empty());
}

// One slice of 256 x 256 is 1/256 of the box thick: at the presets' opacity (0.02 per 1/256)
// a ray straight across gathers 2%, which the user must hear about; an opaque transfer
// function shows it, and a volume of 64 slices is no thin volume.
TEST(VolumeWarnings, AVolumeTooThinForItsOpacityIsSaid) {
  const Scene preset = sceneOf(false);
  const auto w = volumeWarnings(preset, shape({256, 256, 1}));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0],
            "data/slice.yaml: volume: 1 voxel thick along z, 1/256 of the box's largest side: opacity counts per 1/256 "
            "of that side, so a ray straight across gathers at most 2% (the transfer function's highest opacity is "
            "0.02) and the image is faint; give transfer_function points more opacity (`a` up to 1)");
  // Along y, three voxels of spacing 0.5 in a 300-wide box.
  const auto y = volumeWarnings(preset, shape({300, 3, 200}, {1, 0.5, 1}));
  ASSERT_EQ(y.size(), 1u);
  EXPECT_NE(y[0].find("3 voxels thick along y, 1.28/256"), std::string::npos) << y[0];
  Scene opaque = sceneOf(false);
  opaque.tf = TransferFunction({{0, 0, 0, 0, 0}, {1, 1, 1, 1, 0.9}});
  EXPECT_TRUE(volumeWarnings(opaque, shape({256, 256, 1})).empty());
  EXPECT_TRUE(volumeWarnings(preset, shape({256, 256, 64})).empty());
}

// tessera-info's advice names what lies apart and the `range` to give, only when the scene
// gives none.
TEST(VolumeWarnings, ARangeIsSuggestedForCtPaddingUnlessTheSceneGivesOne) {
  ValueHistogram h(-3024, 1500, 4096, true);  // bins of 1.1 values: the first may hold -3023 too
  h.counts[0] = 200000;
  for (int v = -1024; v <= 1500; ++v)
    for (int k = 0; k < 300; ++k) h.add(v);
  EXPECT_EQ(rangeSuggestion(sceneOf(false), h),
            "data/slice.yaml: volume: 21% of the voxels lie apart below the rest, at -3024 .. -3023; with no `range` the "
            "transfer function spans the data's whole -3024 .. 1500: `range: [-1024, 1500]` (79.1% of the voxels) "
            "spends it on the rest (values outside clamp to its ends)");
  EXPECT_EQ(rangeSuggestion(sceneOf(true, {-1000, 1000}), h), "");
}

// Values far from 0 with a small spread: the advice prints digits enough to tell its ends
// apart (it suggested `range: [1e+09, 1e+09]`, which the scene parser refuses: found by review).
TEST(VolumeWarnings, ASuggestedRangeHasTheDigitsItsEndsNeed) {
  ValueHistogram h(1e9, 1e9 + 1000, 4096, false);
  for (int k = 0; k <= 20000; ++k) h.add(1e9 + k / 5000.0);  // 1e9 .. 1e9 + 4
  h.add(1e9 + 1000), h.add(1e9 + 1000);
  const std::string advice = rangeSuggestion(sceneOf(false), h);
  EXPECT_NE(advice.find("the transfer function spans the data's whole 1000000000 .. 1000001000: `range: [1000000000, "
                        "1000000004"), std::string::npos) << "advice: " << advice;
  EXPECT_EQ(digitsToTell(1e9, 1e9 + 4), 10);
  EXPECT_EQ(digitsToTell(0.1, 0.2), 9);
  EXPECT_EQ(digitsToTell(5, 5), 9);
}

// A microscope's background: most voxels in one peak at the low end (a camera offset of 100
// and noise of 40), the cell's values spread above it. The default colour map gives the peak
// enough opacity to be a haze; the advice starts the range past its tail (where it falls to
// 1% of its height: 100 + 40 * sqrt(2 ln 100) = 221). A colour map that leaves it
// transparent, or a scene that gives a range, gets none.
TEST(VolumeWarnings, ARangeIsSuggestedPastABackgroundThePresetMakesAHaze) {
  ValueHistogram h(0, 4000, 4096, true);
  for (int v = 0; v <= 400; ++v) h.counts[std::min<size_t>(4095, (size_t)(v * 4096 / 4000))] +=
      (uint64_t)std::llround(1e6 * std::exp(-0.5 * (v - 100) * (v - 100) / 1600.0));
  for (int v = 300; v <= 4000; ++v) h.counts[std::min<size_t>(4095, (size_t)(v * 4096 / 4000))] += 10000;  // 27%
  const std::string advice = rangeSuggestion(sceneOf(false), h);
  EXPECT_NE(advice.find("lie in one peak at the low end, 0 .. "), std::string::npos) << advice;
  const size_t at = advice.find("`range: [");
  ASSERT_NE(at, std::string::npos) << advice;
  const double start = std::atof(advice.c_str() + at + 9);
  EXPECT_GE(start, 210) << advice;
  EXPECT_LE(start, 230) << advice;
  Scene clear = sceneOf(false);
  clear.tf = TransferFunction({{0, 0, 0, 0, 0}, {0.2, 0, 0, 0, 0}, {1, 1, 1, 1, 0.5}});
  EXPECT_EQ(rangeSuggestion(clear, h), "");
  EXPECT_EQ(rangeSuggestion(sceneOf(true, {0, 4000}), h), "");
  Scene windowed = sceneOf(false);  // the scene chose the values its map spans: a range would clip them
  windowed.window = ValueWindow{1000, 800};
  EXPECT_EQ(rangeSuggestion(windowed, h), "");

  // 8-bit data in the same 4096 bins: 15 of every 16 bins empty between the values. The peak
  // (10 +- 3) ends at 10 + 3 * 3.03 = 19.1; a window of 8 bins used to stop inside it.
  ValueHistogram b(0, 255, 4096, true);
  for (int v = 0; v <= 30; ++v) b.add(v), b.counts[(size_t)(v * 4096 / 256)] += (uint64_t)std::llround(1e6 * std::exp(-0.5 * (v - 10) * (v - 10) / 9.0));
  for (int v = 25; v <= 255; ++v) b.counts[(size_t)(v * 4096 / 256)] += 10000;
  const std::string byte_advice = rangeSuggestion(sceneOf(false), b);
  const size_t byte_at = byte_advice.find("`range: [");
  ASSERT_NE(byte_at, std::string::npos) << byte_advice;
  const double byte_start = std::atof(byte_advice.c_str() + byte_at + 9);
  EXPECT_GE(byte_start, 18) << byte_advice;
  EXPECT_LE(byte_start, 22) << byte_advice;
}

}  // namespace
}  // namespace tessera
