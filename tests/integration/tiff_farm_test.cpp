// A microscopist's TIFF stack on the farm: a multi-page 16-bit file (LZW, strips of 4 rows,
// as scanners save them) renders as tessera-render renders it, each renderer decoding only the
// strips of its bricks' rows; tessera-info takes the file alone.
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "tests/common/tiff_writer.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

constexpr int kW = 48, kH = 96, kD = 64;

// A cell-like blob (bright nucleus in a dimmer body) on a dark background, 0.5 um across and
// 2 um between slices, in ImageJ's metadata.
fs::path writeStack(const FarmDir& dir) {
  const fs::path file = dir.path() / "cells.tif";
  TIFF* t = TIFFOpen(file.c_str(), "w");
  EXPECT_NE(t, nullptr);
  std::vector<uint16_t> row(kW);
  for (int z = 0; z < kD; ++z) {
    tiff_writer::pageFields(t, kW, kH, COMPRESSION_LZW);
    TIFFSetField(t, TIFFTAG_PREDICTOR, PREDICTOR_HORIZONTAL);
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)4);
    TIFFSetField(t, TIFFTAG_XRESOLUTION, 2.0f);
    TIFFSetField(t, TIFFTAG_YRESOLUTION, 2.0f);
    if (z == 0) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, "ImageJ=1.54f\nimages=64\nslices=64\nunit=micron\nspacing=2\n");
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const double body = std::hypot((x - 24) / 20.0, (y - 48) / 38.0, (z - 32) / 10.0);
        const double nucleus = std::hypot((x - 28) / 8.0, (y - 40) / 8.0, (z - 32) / 4.0);
        row[x] = (uint16_t)(nucleus < 1 ? 3000 : body < 1 ? 900 + 300 * std::sin(x * 0.5 + z * 0.2) : 120 + (x + y) % 7);
      }
      EXPECT_EQ(TIFFWriteScanline(t, row.data(), (uint32_t)y, 0), 1);
    }
    EXPECT_EQ(TIFFWriteDirectory(t), 1);
  }
  TIFFClose(t);
  return file;
}

TEST(TiffFarm, AMicroscopeStackRendersOnTheFarmAsTesseraRenderRendersIt) {
  FarmDir dir("tiff-farm");
  writeStack(dir);
  const fs::path scene = dir.path() / "cells.yaml";
  std::ofstream(scene) << "volume: {file: cells.tif, range: [0, 3200]}\nimage: [48, 64]\n"
                          "transfer_function: [[0, 0, 0, 0, 0], [0.1, 0.2, 0.8, 0.3, 0], [0.3, 0.3, 0.9, 0.4, 0.08], "
                          "[1, 1, 0.9, 0.3, 0.8]]\n";
  const auto r = dir.runFarm(scene, 2, 1, 1);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(dir.matches(dir.farmFrame(0), dir.reference(scene, 0), 1, "tiff"));
  // The bricks split the rows (y is the longest axis): each renderer read its half of the rows
  // of the 64 pages of 48 x 96 uint16 (0.56 MiB), plus a ghost row (0.29 MiB), and decoded
  // only the strips that hold them (whole pages would be 0.56 MiB).
  const std::vector<double> read = renderersRead(r.output);
  EXPECT_EQ(read.size(), 2u) << r.output;
  for (double mib : read) EXPECT_LT(mib, 0.4) << "a renderer read more than its bricks\n" << r.output;
  const std::regex decoded_line(R"(MiB of volume samples \(([0-9.]+) MiB decompressed\))");
  int decoders = 0;
  for (auto it = std::sregex_iterator(r.output.begin(), r.output.end(), decoded_line); it != std::sregex_iterator(); ++it, ++decoders)
    EXPECT_LT(std::stod((*it)[1].str()), 0.4) << "a renderer decoded strips of rows it does not render\n" << r.output;
  EXPECT_EQ(decoders, 2) << r.output;

  const auto info = runCommand(bin("tessera-info") + " " + (dir.path() / "cells.tif").string() + " --bins 4", 60);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("volume: 48 x 96 x 64 voxels, uint16, spacing 0.5 0.5 2"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("values: 120 .. 3000;"), std::string::npos) << info.output;
}

}  // namespace
}  // namespace tessera::test
