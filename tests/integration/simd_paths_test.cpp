// One binary, every instruction set: tessera-render picks the fast kernel for the CPU, and
// each lower level TESSERA_SIMD can force (down to the scalar path of CPUs without AVX2)
// renders the same image bit for bit: the kernel's arithmetic is explicit (fused
// multiply-adds in every path), so the instruction set must not change a single value.
#include <gtest/gtest.h>

#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

std::string simdOf(const std::string& stats_output) {
  std::smatch m;
  return std::regex_search(stats_output, m, std::regex("simd=(\\w+)")) ? m[1].str() : "";
}

TEST(SimdPaths, EveryLevelTheCpuHasRendersTheSameImage) {
  FarmDir dir("simd");
  const auto scene = dir.writeScene(1, 48, 160, 120).string();
  auto render = [&](const std::string& level) {
    const std::string pam = (dir.path() / ("simd-" + level + ".pam")).string();
    const auto r = runCommand((level.empty() ? "" : "env TESSERA_SIMD=" + level + " ") + bin("tessera-render") + " " +
                                  scene + " --stats -o " + dir.path().string() + "/x.png --premultiplied " + pam,
                              120);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return std::pair{simdOf(r.output), readPam(pam)};
  };
  const auto [best, image] = render("");
  ASSERT_FALSE(best.empty()) << "tessera-render --stats does not name its kernel";
  int levels = 0;
  for (const std::string level : {"scalar", "avx2", "avx512"}) {
    const auto [used, other] = render(level);
    EXPECT_EQ(used, level);
    EXPECT_TRUE(dir.matches(other, image, 0, level + "_vs_" + best));
    ++levels;
    if (level == best) break;
  }
  EXPECT_GE(levels, 1);
}

TEST(SimdPaths, ALevelAboveTheCpuOrAnUnknownWordIsRefused) {
  FarmDir dir("simd-bad");
  const auto r = runCommand("env TESSERA_SIMD=sse9 " + bin("tessera-render") + " -o " + dir.path().string() + "/x.png", 60);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("TESSERA_SIMD=sse9: expected scalar, avx2 or avx512"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace tessera::test
