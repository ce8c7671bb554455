// How a TIFF stack is shown: from where Fiji shows it (the camera of a scene without one),
// and what its metadata leaves to a guess, said (pages ImageJ calls channels or time points,
// read as z slices; a spacing the file lacks).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/scene.h"
#include "common/scene_warnings.h"
#include "tests/common/load_error.h"
#include "tests/common/temp_dir.h"
#include "tests/common/tiff_writer.h"

namespace tessera {
namespace {
namespace tiff_view_test {

using test::TempDir;
using test::tiff_writer::kNz, test::tiff_writer::PageOptions, test::tiff_writer::writePages;

Scene sceneOf(const TempDir& t, const std::string& volume) {
  return parseScene("volume: " + volume + "\nimage: [200, 100]\n", t.path.string(), "s.yaml");
}

// Where a corner of slice 0's page lands in the image, as fractions of its width and height.
std::array<double, 2> onScreen(const Scene& s, double x_sign, double y_sign) {
  const Vec3 h = sceneHalfExtent(s);
  double sx = 0, sy = 0;
  EXPECT_TRUE(RayGenerator(s.camera, s.width, s.height).project({x_sign * h.x, y_sign * h.y, -h.z}, sx, sy));
  return {sx / s.width, sy / s.height};
}

bool hasWarning(const Scene& s, const std::string& what) {
  const Volume v = loadVolume(s);
  const std::vector<std::string> w = volumeWarnings(s, v);
  return std::any_of(w.begin(), w.end(), [&](const std::string& x) { return x.find(what) != std::string::npos; });
}

// Fiji shows a page with its first row at the top and its first column at the left, slice 0
// in front. A raw file (whose rows have no such convention) keeps the view from +z.
TEST(TiffView, AStackIsSeenAsFijiShowsIt) {
  TempDir t("tiff-view");
  writePages(t.file("v.tif"), 0, kNz);
  const Scene s = sceneOf(t, "{file: v.tif}");
  const auto first = onScreen(s, -1, -1), last = onScreen(s, 1, 1);  // row 0, column 0; the last row and column
  EXPECT_LT(first[0], 0.5);
  EXPECT_LT(first[1], 0.5) << "row 0 is drawn in the lower half";
  EXPECT_GT(last[0], 0.5);
  EXPECT_GT(last[1], 0.5);
  const Vec3 h = sceneHalfExtent(s);
  EXPECT_LT(length(s.camera.eye - Vec3{0, 0, -h.z}), length(s.camera.eye - Vec3{0, 0, h.z})) << "slice 0 is not in front";

  const auto v = test::tiff_writer::samples();
  t.write("v.raw", v.data(), v.size() * 2);
  const Scene raw = sceneOf(t, "{file: v.raw, dims: [13, 11, 7], type: uint16}");
  EXPECT_GT(onScreen(raw, -1, -1)[1], 0.5) << "a raw file's row 0 is at the bottom, as before";
}

// tifffile's imagej=True without axes calls every page a channel; Fiji may call a z-stack's
// slices time points. One such axis alone is read as z, and said; two are still refused.
TEST(TiffView, PagesImageJCallsChannelsOrTimePointsAreReadAsSlicesAndSaid) {
  TempDir t("tiff-axes");
  PageOptions o;
  o.description = "ImageJ=1.54f\nimages=7\nchannels=7\n";
  writePages(t.file("c.tif"), 0, kNz, o);
  o.description = "ImageJ=1.54f\nimages=7\nframes=7\n";
  writePages(t.file("f.tif"), 0, kNz, o);
  writePages(t.file("z.tif"), 0, kNz);
  const Volume z = loadVolume(sceneOf(t, "{file: z.tif}"));
  for (const char* f : {"c.tif", "f.tif"}) {
    const Scene s = sceneOf(t, std::string("{file: ") + f + "}");
    EXPECT_EQ(loadVolume(s).values, z.values) << f;
  }
  EXPECT_TRUE(hasWarning(sceneOf(t, "{file: c.tif}"), "calls its 7 pages channels; Tessera reads them as z slices"));
  EXPECT_TRUE(hasWarning(sceneOf(t, "{file: f.tif}"), "calls its 7 pages time points; Tessera reads them as z slices"));
  EXPECT_FALSE(hasWarning(sceneOf(t, "{file: z.tif}"), "Tessera reads them as z slices"));
  o.description = "ImageJ=1.54f\nimages=6\nchannels=2\nframes=3\nhyperstack=true\n";
  writePages(t.file("cf.tif"), 0, 6, o);
  const std::string e = test::loadError("volume: {file: cf.tif}\n", t.path.string());
  EXPECT_NE(e.find("an ImageJ hyperstack of 2 channels"), std::string::npos) << e;
  o.description = "ImageJ=1.54f\nimages=7\nchannels=1e20\n";  // not a count: refused, not cast
  writePages(t.file("huge.tif"), 0, kNz, o);
  const std::string huge = test::loadError("volume: {file: huge.tif}\n", t.path.string());
  EXPECT_NE(huge.find("ImageJ's metadata says channels="), std::string::npos) << huge;
}

// A spacing the file does not give is 1, and said, unless the scene gives one.
TEST(TiffView, ASpacingTheFileLacksIsSaid) {
  TempDir t("tiff-spacing");
  writePages(t.file("plain.tif"), 0, kNz);
  PageOptions o;
  o.description = "ImageJ=1.54f\nimages=7\nslices=7\nunit=micron\n";
  o.resolution = 4;
  writePages(t.file("no-z.tif"), 0, kNz, o);
  o.description += "spacing=2.5\n";
  writePages(t.file("all.tif"), 0, kNz, o);
  EXPECT_TRUE(hasWarning(sceneOf(t, "{file: plain.tif}"), "gives no voxel spacing along x, y, z: 1 assumed"));
  const Scene no_z = sceneOf(t, "{file: no-z.tif}");
  EXPECT_EQ(loadVolume(no_z).spacing, (std::array<double, 3>{0.25, 0.25, 1}));
  EXPECT_TRUE(hasWarning(no_z, "gives no voxel spacing along z: 1 assumed"));
  EXPECT_FALSE(hasWarning(sceneOf(t, "{file: all.tif}"), "gives no voxel spacing"));
  EXPECT_FALSE(hasWarning(sceneOf(t, "{file: plain.tif, spacing: [1, 1, 2]}"), "gives no voxel spacing"));
}

}  // namespace tiff_view_test
}  // namespace
}  // namespace tessera
