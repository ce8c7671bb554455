// One binary, every instruction set: tessera-render picks the fast kernel for the CPU, and
// each lower level TESSERA_SIMD can force (down to the scalar path of CPUs without AVX2)
// renders the same image bit for bit: the kernel's arithmetic is explicit (fused
// multiply-adds in every path), so the instruction set must not change a single value. Nor
// may the way the vector kernels read voxels (TESSERA_GATHER: gather instructions or lanes).
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

std::string statOf(const std::string& stats_output, const std::string& key) {
  std::smatch m;
  return std::regex_search(stats_output, m, std::regex(key + "=(\\w+)")) ? m[1].str() : "";
}

// Shading: the vector kernels light eight samples at once, the portable one sample by sample.
// `lighting` is appended to the scene ("" unlit; a specular headlight; a fixed light).
class SimdPaths : public ::testing::TestWithParam<const char*> {};

TEST_P(SimdPaths, EveryLevelTheCpuHasRendersTheSameImage) {
  FarmDir dir("simd");
  // The default scene's transfer function (transparent below 0.05: empty space to skip, a
  // translucent shell, an opaque core) on a small shell.
  const std::string scene = (dir.path() / "scene.yaml").string();
  std::ofstream(scene) << "volume:\n  generator: {name: hollow-shell, size: 48, seed: 1}\n"
                       << "transfer_function:\n  - [0.00, 0.0, 0.0, 0.0, 0.0]\n  - [0.05, 1.0, 0.45, 0.1, 0.0]\n"
                       << "  - [0.50, 1.0, 0.55, 0.15, 0.06]\n  - [0.70, 1.0, 0.8, 0.5, 0.2]\n"
                       << "  - [1.00, 1.0, 1.0, 0.9, 0.9]\n"
                       << "camera: {eye: [0.3, 0.5, 2.2], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                       << "image: [160, 120]\nquality: default\n"
                       << GetParam();
  // The float image (--raw), compared bit for bit: a rounding that differs rarely moves a byte.
  // The sample counts (taken, skipped, terminated) show the empty-space and termination
  // decisions, which an image cannot; with and without skipping (two loops of the kernel).
  struct Render {
    std::string simd, gather, counts, floats;
    Image8 image;
  };
  auto render = [&](const std::string& level, const std::string& gather, const std::string& flags) {
    const std::string pam = (dir.path() / ("simd-" + level + gather + ".pam")).string();
    const std::string raw = (dir.path() / ("simd-" + level + gather + ".f32")).string();
    const std::string env = (level.empty() ? "" : " TESSERA_SIMD=" + level) + (gather.empty() ? "" : " TESSERA_GATHER=" + gather);
    const auto r = runCommand((env.empty() ? "" : "env" + env + " ") + bin("tessera-render") + " " +
                                  scene + " --stats " + flags + " -o " + dir.path().string() + "/x.png --premultiplied " +
                                  pam + " --raw " + raw,
                              120);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::smatch m;
    const std::string counts =
        std::regex_search(r.output, m, std::regex("samples=\\d+ skipped=(\\d+) terminated=\\d+")) ? m[0].str() : "";
    if (flags.empty()) {
      EXPECT_NE(m[1].str(), "0") << "nothing skipped: the scene does not test the leaper";
    }
    std::ifstream in(raw, std::ios::binary);
    return Render{statOf(r.output, "simd"), statOf(r.output, "gather"), counts,
                  std::string(std::istreambuf_iterator<char>(in), {}), readPam(pam)};
  };
  for (const std::string flags : {"", "--no-skip"}) {
    SCOPED_TRACE("flags '" + flags + "'");
    const Render best = render("", "", flags);
    ASSERT_FALSE(best.simd.empty()) << "tessera-render --stats does not name its kernel";
    ASSERT_FALSE(best.gather.empty()) << "tessera-render --stats does not say how it reads voxels";
    ASSERT_FALSE(best.counts.empty()) << "tessera-render --stats prints no sample counts";
    ASSERT_GT(best.floats.size(), 160u * 120 * 16 - 1) << "no float image";
    int levels = 0;
    for (const std::string level : {"scalar", "avx2", "avx512"}) {
      // The portable kernel reads one sample at a time: TESSERA_GATHER changes nothing there.
      for (const std::string gather : {"lanes", "hardware"}) {
        if (level == "scalar" && gather == "hardware") continue;
        const std::string name = level + "/" + gather;
        const Render other = render(level, gather, flags);
        EXPECT_EQ(other.simd, level);
        EXPECT_EQ(other.gather, gather);
        EXPECT_EQ(other.counts, best.counts) << name << " against " << best.simd << "/" << best.gather;
        EXPECT_TRUE(other.floats == best.floats) << name << " and " << best.simd << "/" << best.gather
                                                 << " differ in their float images";
        EXPECT_TRUE(dir.matches(other.image, best.image, 0, level + "_" + gather + "_vs_best"));
        ++levels;
      }
      if (level == best.simd) break;
    }
    EXPECT_GE(levels, 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Lighting, SimdPaths,
                         ::testing::Values("", "shading: {specular: 0.4, shininess: 12}\n",
                                           "shading: {ambient: 0.2, diffuse: 0.6, specular: 0.3}\nlight: [-1, 1, 1]\n"));

TEST(SimdLevel, ALevelAboveTheCpuOrAnUnknownWordIsRefused) {
  FarmDir dir("simd-bad");
  const auto r = runCommand("env TESSERA_SIMD=sse9 " + bin("tessera-render") + " -o " + dir.path().string() + "/x.png", 60);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("TESSERA_SIMD=sse9: expected scalar, avx2 or avx512"), std::string::npos) << r.output;
}

TEST(SimdLevel, AnUnknownWayOfReadingVoxelsIsRefused) {
  FarmDir dir("gather-bad");
  const auto r = runCommand("env TESSERA_GATHER=avx " + bin("tessera-render") + " -o " + dir.path().string() + "/x.png", 60);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("TESSERA_GATHER=avx: expected hardware or lanes"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace tessera::test
