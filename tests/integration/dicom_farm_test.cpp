// A clinician's DICOM folder on the farm: a CT series (int16, rescaled to Hounsfield units,
// some slices compressed, files in no particular order) renders as tessera-render renders
// it, each renderer reading only its bricks' slices; tessera-info takes the folder alone.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/common/dicom_writer.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

// 64 x 56 x 40: air (-1000 HU) around a body (40 HU) with a bone ball (1000 HU), stored
// +1024 as scanners store them; every third slice RLE-compressed.
fs::path writeCt(const FarmDir& dir) {
  const fs::path folder = dir.path() / "ct";
  fs::create_directories(folder);
  for (int k = 0; k < 40; ++k) {
    DicomSlice s;
    s.cols = 64, s.rows = 56, s.z = 2.0 * k, s.sx = s.sy = 1.5, s.inter = -1024;
    s.syntax = k % 3 ? gdcm::TransferSyntax::ExplicitVRLittleEndian : gdcm::TransferSyntax::RLELossless;
    for (int y = 0; y < s.rows; ++y)
      for (int x = 0; x < s.cols; ++x) {
        const double body = std::hypot((x - 32) / 28.0, (y - 28) / 22.0);
        const double ball = std::sqrt(std::pow(x - 40, 2) + std::pow(y - 24, 2) + std::pow((k - 20) * 1.33, 2));
        const int hu = ball < 9 ? 1000 : body < 1 ? 40 + (int)(20 * std::sin(x * 0.4 + k * 0.3)) : -1000;
        s.values.push_back((int16_t)(hu + 1024));
      }
    writeDicomSlice(folder / ("IMG" + std::to_string((k * 17) % 40)), s);
  }
  return folder;
}

TEST(DicomFarm, ACtSeriesRendersOnTheFarmAsTesseraRenderRendersIt) {
  FarmDir dir("dicom-farm");
  writeCt(dir);
  const fs::path scene = dir.path() / "ct.yaml";
  std::ofstream(scene) << "volume: {file: ct, range: [-200, 1200]}\nimage: [64, 48]\n"
                          "transfer_function: [[0, 0, 0, 0, 0], [0.15, 0.9, 0.5, 0.4, 0.05], [1, 1, 1, 1, 0.6]]\n";
  const auto r = dir.runFarm(scene, 2, 1, 1);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(dir.matches(dir.farmFrame(0), dir.reference(scene, 0), 1, "dicom"));
  // Each renderer read its half of the 40 slices of 64 x 56 int16 (280 KiB), plus ghost slices.
  const std::vector<double> read = renderersRead(r.output);
  EXPECT_EQ(read.size(), 2u) << r.output;
  for (double mib : read) EXPECT_LT(mib, 0.2) << "a renderer read more than its bricks\n" << r.output;

  const auto info = runCommand(bin("tessera-info") + " " + (dir.path() / "ct").string() + "/ --bins 4", 60);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("volume: 64 x 56 x 40 voxels, int16, spacing 1.5 1.5 2"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("values: -1000 .. 1000;"), std::string::npos) << info.output;
}

}  // namespace
}  // namespace tessera::test
