// Data where it is rendered: each renderer of a farm loads only its bricks and their ghost
// voxels from the user's raw file (positioned reads), the master only streams a summary,
// and the frames still match the one-process render of the whole file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <regex>
#include <vector>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(FarmWindows, RenderersLoadOnlyTheirBricksAndTheFramesMatchOneProcess) {
  FarmDir dir("windows");
  // A 48 x 40 x 36 uint16 blob whose values (0..2000) are far below the type's range: the
  // farm must normalise every window with the whole file's min..max, as tessera-render does.
  const int nx = 48, ny = 40, nz = 36;
  std::vector<uint16_t> v((size_t)nx * ny * nz);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const double r = std::hypot((x - 20.0) / 18, (y - 21.0) / 15, (z - 17.0) / 14);
        v[x + (size_t)nx * (y + (size_t)ny * z)] = (uint16_t)std::lround(std::max(0.0, 2000 * (1 - r)) + (x % 5) * 3);
      }
  std::ofstream(dir.path() / "blob.raw", std::ios::binary)
      .write(reinterpret_cast<const char*>(v.data()), (std::streamsize)(v.size() * 2));
  const fs::path scene = dir.path() / "blob.yaml";
  std::ofstream(scene) << "volume: {file: blob.raw, dims: [48, 40, 36], type: uint16, spacing: [1, 1, 1.2]}\n"
                          "image: [64, 48]\norbit: {frames: 8, axis: [0, 1, 0]}\n";
  const auto r = dir.runFarm(scene, 3, 1, 2);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int k = 0; k < 2; ++k)
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << k;
  // Each renderer said which voxels it loaded: once (its bricks do not move), and a box
  // much smaller than the volume.
  const std::regex loaded(R"(loaded voxels \[(\d+), (\d+), (\d+)\] \.\. \[(\d+), (\d+), (\d+)\))");
  const std::string log = r.output;
  int loads = 0;
  long long held = 0;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), loaded); it != std::sregex_iterator(); ++it) {
    const auto& m = *it;
    long long voxels = 1;
    for (int a = 0; a < 3; ++a) voxels *= std::stoll(m[4 + a]) - std::stoll(m[1 + a]);
    EXPECT_LT(voxels, (long long)nx * ny * nz * 2 / 3) << m[0];
    held += voxels;
    ++loads;
  }
  EXPECT_EQ(loads, 3) << log;
  // Three bricks and their ghost layers: the volume once, plus the faces they share.
  EXPECT_LT(held, (long long)nx * ny * nz * 13 / 10) << log;
}

}  // namespace
}  // namespace tessera::test
