// The farm's frames equal the one-process render (docs/DESIGN.md accuracy contract: sort-last,
// rgba8, max abs <= 1/255 per channel), for 1, 2 and 4 renderers and 1 and 2 compositors.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <nlohmann/json.hpp>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

struct Shape {
  int renderers, compositors;
};

class FarmMatchesOneProcess : public ::testing::TestWithParam<Shape> {};

TEST_P(FarmMatchesOneProcess, EveryFrameWithinOneLevel) {
  const auto [renderers, compositors] = GetParam();
  FarmDir dir("match-" + std::to_string(renderers) + "x" + std::to_string(compositors));
  const int frames = 3;
  auto scene = dir.writeScene(6);
  auto run = dir.runFarm(scene, renderers, compositors, frames);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    Image8 farm = readPng(dir.frame(k).string());
    Image8 ref = dir.reference(scene, k);
    // 1/255: each brick's piece is quantized to rgba8 once before compositing.
    EXPECT_LE(maxAbsDiff(farm, ref), 1) << "frame " << k << " in " << dir.path();
    EXPECT_GT(activeRegion(farm).area(), 100) << "frame " << k << " is (nearly) empty";
  }
  // One metrics line per frame, with every stage's report in it.
  std::ifstream metrics(dir.path() / "out" / "metrics.jsonl");
  int lines = 0;
  for (std::string line; std::getline(metrics, line); ++lines) {
    auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["render_reports"].get<int>(), renderers);
    EXPECT_EQ(j["composite_reports"].get<int>(), compositors);
    EXPECT_GT(j["render_bytes_raw"].get<uint64_t>(), 0u);
    EXPECT_LT(j["render_bytes_encoded"].get<uint64_t>(), j["render_bytes_raw"].get<uint64_t>() + 1024);
  }
  EXPECT_EQ(lines, frames);
}

INSTANTIATE_TEST_SUITE_P(Shapes, FarmMatchesOneProcess,
                         ::testing::Values(Shape{1, 1}, Shape{2, 1}, Shape{2, 2}, Shape{4, 2}),
                         [](const auto& param_info) {
                           return std::to_string(param_info.param.renderers) + "r" + std::to_string(param_info.param.compositors) + "c";
                         });

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

// rgba8 pieces (the smallest on the wire) round each brick's colour and alpha before
// compositing and once more at the end: |error| < 1.5 levels, so 2/255 is the bound
// this mode can promise (the default rgba16f keeps the 1/255 contract, above).
TEST(FarmPixelFormats, Rgba8PiecesStayWithinTwoLevels) {
  FarmDir dir("rgba8");
  auto scene = dir.writeScene(4);
  auto run = dir.runFarm(scene, 4, 1, 2, 120, "--env TESSERA_FORMAT=rgba8");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < 2; ++k) EXPECT_LE(maxAbsDiff(readPng(dir.frame(k).string()), dir.reference(scene, k)), 2);
}

// The same farm over TCP on loopback (what a cluster uses, minus the other hosts): the
// master, display and compositors listen on ports derived from one base.
TEST(FarmTransports, TcpLoopbackMatchesOneProcess) {
  FarmDir dir("tcp");
  auto scene = dir.writeScene(4);
  std::random_device rd;
  const int base = 20000 + (int)(rd() % 20000);  // PORT..PORT+2, PORT+10+rank: a free range is likely
  auto run = dir.runFarm(scene, 2, 2, 2, 120, "", "tcp://127.0.0.1:" + std::to_string(base));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("tcp://127.0.0.1:" + std::to_string(base + 11)), std::string::npos)
      << "compositor 1 should listen on base+11";
  // 1/255: the sort-last contract.
  for (int k = 0; k < 2; ++k) EXPECT_LE(maxAbsDiff(readPng(dir.frame(k).string()), dir.reference(scene, k)), 1);
}

TEST(FarmPixelFormats, Rgba32fPiecesKeepTheContract) {
  FarmDir dir("rgba32f");
  auto scene = dir.writeScene(4);
  auto run = dir.runFarm(scene, 4, 2, 2, 120, "--env TESSERA_FORMAT=rgba32f --env TESSERA_CODEC=lz4");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // 1/255: float pieces, one rounding at the end.
  for (int k = 0; k < 2; ++k) EXPECT_LE(maxAbsDiff(readPng(dir.frame(k).string()), dir.reference(scene, k)), 1);
}

}  // namespace
}  // namespace tessera::test
