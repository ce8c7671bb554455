// The scene's colour `window` (in the volume's own values) through a farm: the master sends it
// with every frame as a fraction of the range it read from the file (here the data's own, no
// `range` given), and the frames match tessera-render's, which lays the map over the same
// values, within the accuracy contract.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <vector>

#include <fmt/format.h>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

// A 40^3 uint16 ball of values falling from ~4300 at its centre to 500 at radius 20 and
// beyond, so that the data's own range (no `range` given) starts well above 0. Returns its largest value.
int writeBall(const fs::path& file) {
  std::vector<uint16_t> v(40 * 40 * 40);
  for (int z = 0; z < 40; ++z)
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) {
        const double r = std::sqrt((x - 19.5) * (x - 19.5) + (y - 19.5) * (y - 19.5) + (z - 19.5) * (z - 19.5));
        v[x + 40 * (y + 40 * z)] = (uint16_t)(500 + std::lround(std::max(0.0, 4000 * (1 - r / 20))));
      }
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(v.data()), (std::streamsize)(v.size() * 2));
  return *std::max_element(v.begin(), v.end());
}

void runAndCompare(const char* name, const char* blend, int renderers, const char* compositing) {
  FarmDir dir(name);
  const int top = writeBall(dir.path() / "ball.raw");
  const int frames = 3;
  const fs::path scene = dir.path() / "window.yaml";
  std::ofstream(scene) << "volume: {file: ball.raw, dims: [40, 40, 40], type: uint16}\n"
                          "transfer_function: viridis\nwindow: {level: 3100, width: 1500}\nblend: "
                       << blend << "\nimage: [128, 96]\norbit: {frames: " << frames << ", degrees: 90}\n";
  expectFarmMatchesRender(dir, scene, frames, renderers, 1, compositing, 600, name);
  // The window is in the data's values, 500 .. top: as a fraction of that range it is this.
  const Image8 windowed = dir.reference(scene, 0);
  const std::string fraction = fmt::format("--window {:.17g},{:.17g}", (3100.0 - 500) / (top - 500), 1500.0 / (top - 500));
  EXPECT_EQ(maxAbsDiff(windowed, dir.reference(scene, 0, fraction)), 0) << fraction;
  // The window shows: the scene's map over the whole range (window 0.5, 1) differs.
  EXPECT_GT(maxAbsDiff(windowed, dir.reference(scene, 0, "--window 0.5,1")), 16) << "the window changed nothing";
}

TEST(WindowFarm, CompositeMatchesTesseraRender) { runAndCompare("window-composite", "composite", 2, "direct-send"); }

TEST(WindowFarm, MaximumIntensityMatchesTesseraRender) { runAndCompare("window-mip", "maximum", 2, "binary-swap"); }

}  // namespace
}  // namespace tessera::test
