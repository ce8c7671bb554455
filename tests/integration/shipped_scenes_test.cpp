// The accuracy contract on what users run first: every shipped volume scene, as shipped (its
// quality, shading, crop, window and blend), within 40 dB of its reference render. Frame 15 of
// each orbit, where a one-voxel step on the shaded Marschner-Lobb surface gave 37.6 dB; 96².
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(ShippedScenes, EveryVolumeSceneIsWithin40dBOfItsReference) {
  namespace fs = std::filesystem;
  FarmDir dir("shipped-scenes");
  int checked = 0;
  for (const auto& e : fs::directory_iterator(fs::path(TESSERA_SOURCE_DIR) / "scenes")) {
    if (e.path().extension() != ".yaml") continue;
    std::ifstream in(e.path());
    const std::string text(std::istreambuf_iterator<char>(in), {});
    if (std::regex_search(text, std::regex("(^|\n)mesh:"))) continue;  // geometry: bit-identical tilings, tested apart
    const auto r = runCommand(bin("tessera-render") + " " + e.path().string() + " --image 96x96 --frame 15 --compare-reference -o " +
                                  (dir.path() / "x.png").string(),
                              120);
    ASSERT_EQ(r.exit_code, 0) << e.path() << ": " << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex("psnr=([0-9.]+|inf) dB"))) << r.output;
    EXPECT_GE(std::stod(m[1].str()), 40.0) << e.path().filename() << ": " << r.output;
    ++checked;
  }
  EXPECT_GE(checked, 10) << "the shipped volume scenes were not found";
}

}  // namespace
}  // namespace tessera::test
