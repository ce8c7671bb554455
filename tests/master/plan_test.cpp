#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "common/scene.h"
#include "master/plan.h"
#include "master/sort_first_plan.h"
#include "master/sort_last_plan.h"
#include "tests/common/temp_dir.h"

namespace tessera::master {
namespace {

proto::FrameParams sized(int width, int height) {
  proto::FrameParams p;
  p.width = width;
  p.height = height;
  return p;
}

Workers twoByTwo() { return {{0, 2}, {{0, "ep0"}, {3, "ep3"}}}; }

TEST(SortLastPlan, OneBrickPerRendererAndOneBandPerCompositor) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 16, 1};
  SortLastPlan plan(summarizeVolume(scene), scene.tf, true);
  Workers w = twoByTwo();
  plan.reassign(w);
  proto::FrameParams p = sized(64, 48);
  p.camera = scene.camera;
  plan.fill(p, w);
  ASSERT_EQ(p.mode(), proto::FrameMode::SortLast);
  const proto::SortLastWork& work = *p.sortLast();
  ASSERT_EQ(work.bricks.size(), 2u);
  EXPECT_EQ(work.bricks[0].renderer, 0u);
  EXPECT_EQ(work.bricks[1].renderer, 2u);
  EXPECT_EQ(work.order.size(), 2u);
  ASSERT_EQ(p.regions.size(), 2u);
  EXPECT_EQ(p.regions[1].compositor, 3u);
  EXPECT_EQ(p.regions[1].endpoint, "ep3");
  EXPECT_EQ(p.regions[0].region.h + p.regions[1].region.h, 48);
}

// Bricks are sticky: a loss moves only the lost renderer's bricks, to the owner of a
// neighbouring brick in the k-d tree; a join splits again for everyone.
TEST(SortLastPlan, ALostRendererBricksGoToANeighbourAndNoOtherBrickMoves) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 64, 1};
  SortLastPlan plan(summarizeVolume(scene), scene.tf, true);
  auto bricksOf = [&](const Workers& w) {
    proto::FrameParams p = sized(64, 48);
    p.camera = scene.camera;
    plan.fill(p, w);
    return p.sortLast()->bricks;
  };
  Workers w{{0, 1, 2, 4}, {{9, "ep9"}}};
  plan.reassign(w);
  const auto before = bricksOf(w);
  ASSERT_EQ(before.size(), 4u);
  w.renderers = {0, 2, 4};  // renderer 1 lost
  plan.reassign(w);
  const auto after = bricksOf(w);
  ASSERT_EQ(after.size(), 4u);
  for (size_t b = 0; b < 4; ++b) {
    EXPECT_EQ(after[b].brick, before[b].brick) << "brick " << b << " changed shape";
    if (before[b].renderer != 1) {
      EXPECT_EQ(after[b].renderer, before[b].renderer) << "brick " << b << " moved";
    }
  }
  // Renderer 1 had brick 1; the k-d tree pairs bricks 0 and 1 (the first split halves the
  // volume, each half is split again), so renderer 0 takes it and holds their parent box.
  EXPECT_EQ(after[1].renderer, 0u);
  w.renderers = {0, 2, 4, 7};  // a renderer joins: a new split for everyone
  plan.reassign(w);
  const auto joined = bricksOf(w);
  ASSERT_EQ(joined.size(), 4u);
  EXPECT_EQ(joined[3].renderer, 7u);
}

// Binary swap: a plan for any count of renderers with one brick and a swap endpoint each;
// after a loss would leave one holding two bricks, everyone gets one brick again.
TEST(SortLastPlan, SwapPlanForOneBrickEachAndEveryRendererWithASwapSocket) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 64, 1};
  SortLastPlan plan(summarizeVolume(scene), scene.tf, true, /*binary_swap=*/true);
  auto fill = [&](const Workers& w) {
    proto::FrameParams p = sized(64, 48);
    p.camera = scene.camera;
    plan.fill(p, w);
    // A binary-swap frame's bands go to the display: no compositor region; else regions tile the image.
    EXPECT_EQ(p.regions.empty(), !p.sortLast()->swap.empty());
    return *p.sortLast();
  };
  Workers w{{0, 1, 2, 4}, {{9, "ep9"}}, {"r0", "r1", "r2", "r4"}};
  plan.reassign(w);
  auto work = fill(w);
  ASSERT_EQ(work.swap.size(), 4u);
  for (size_t b = 0; b < 4; ++b) {
    EXPECT_EQ(work.swap[b].renderer, work.bricks[b].renderer);
    EXPECT_EQ(work.swap[b].endpoint, "r" + std::to_string(work.bricks[b].renderer));
  }
  Workers no_socket = w;
  no_socket.renderer_endpoints[2] = "";  // renderer 2 could not bind its swap socket
  EXPECT_TRUE(fill(no_socket).swap.empty());
  EXPECT_TRUE(plan.needsCompositors(no_socket)) << "its frames go by direct send";
  EXPECT_FALSE(plan.needsCompositors(w));
  w = {{0, 2, 4}, {{9, "ep9"}}, {"r0", "r2", "r4"}};  // renderer 1 lost: a new split of three, swapped (radix-k)
  plan.reassign(w);
  work = fill(w);
  ASSERT_EQ(work.bricks.size(), 3u);
  EXPECT_EQ(work.swap.size(), 3u);
  w = {{2}, {}, {"r2"}};  // one renderer and no compositor left: it sends the display its image
  plan.reassign(w);
  work = fill(w);
  ASSERT_EQ(work.bricks.size(), 1u);
  EXPECT_EQ(work.swap.size(), 1u);
  EXPECT_FALSE(plan.needsCompositors(w));
  w = {{0, 2}, {{9, "ep9"}}, {"r0", "r2"}};
  SortLastPlan direct(summarizeVolume(scene), scene.tf, true);
  direct.reassign(w);
  proto::FrameParams p = sized(64, 48);
  p.camera = scene.camera;
  direct.fill(p, w);
  EXPECT_TRUE(p.sortLast()->swap.empty()) << "direct send unless asked";
  EXPECT_TRUE(direct.needsCompositors(w));
}

TEST(SortLastPlan, BandsFollowTheLatestFramesActivePixels) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 16, 1};
  SortLastPlan plan(summarizeVolume(scene), scene.tf, true);
  Workers w = twoByTwo();
  plan.reassign(w);
  for (uint64_t f : {1, 3}) {
    proto::FrameParams issued = sized(64, 48);
    issued.frame = f;
    plan.fill(issued, w);
  }
  proto::StageStats s;
  s.frame = 3;
  s.active = {0, 0, 64, 8};  // everything in the top rows
  plan.stats(s, w);
  s.frame = 1;
  s.active = {0, 40, 64, 8};  // an older frame: ignored
  plan.stats(s, w);
  proto::FrameParams p = sized(64, 48);
  p.frame = 4;
  plan.fill(p, w);
  ASSERT_EQ(p.regions.size(), 2u);
  EXPECT_LT(p.regions[0].region.h, 24) << "the first band should shrink onto the active rows";
  // A reduced (interactive) frame: the same balance at its own size, its bands tiling it.
  proto::FrameParams half = sized(32, 24);
  half.frame = 5;
  plan.fill(half, w);
  ASSERT_EQ(half.regions.size(), 2u);
  EXPECT_LT(half.regions[0].region.h, 12);
  EXPECT_EQ(half.regions[0].region.h + half.regions[1].region.h, 24);
  EXPECT_EQ(half.regions[1].region.y + half.regions[1].region.h, 24);
  EXPECT_EQ(half.regions[0].region.w, 32);
}

// The bricks hold equal shares of what the map shows through the scene's `window`: a ramp
// along x whose top quarter alone shows (as a CT windowed on bone) is split inside that quarter.
TEST(SortLastPlan, BricksAreBalancedByWhatTheScenesWindowShows) {
  test::TempDir dir("plan_window");
  std::vector<uint8_t> ramp(128 * 8 * 8);
  for (size_t i = 0; i < ramp.size(); ++i) ramp[i] = (uint8_t)(2 * (i % 128));
  dir.write("ramp.raw", ramp.data(), ramp.size());
  const std::string volume = "volume: {file: ramp.raw, dims: [128, 8, 8], type: uint8, range: [0, 255]}\n"
                             "transfer_function: [[0, 0, 0, 0, 0], [1, 1, 1, 1, 1]]\n";
  auto brickXs = [&](const std::string& yaml) {
    const Scene scene = parseScene(yaml, dir.path.string(), "s.yaml");
    auto plan = makePlan(scene, true, 1, false, summarizeVolume(scene));
    const Workers w = twoByTwo();
    plan->reassign(w);
    proto::FrameParams p = sized(64, 48);
    p.camera = scene.camera;
    plan->fill(p, w);
    std::vector<std::array<int, 2>> xs;
    for (const auto& b : p.sortLast()->bricks) xs.push_back({b.brick.lo[0], b.brick.hi[0]});
    std::sort(xs.begin(), xs.end());
    return xs;
  };
  using Xs = std::vector<std::array<int, 2>>;
  EXPECT_EQ(brickXs(volume), (Xs{{0, 64}, {64, 128}}));  // every value but 0 shows
  // Level 232, width 64: values above 200 show, x from 100 on (the summary's blocks of so
  // small a volume are 2 voxels wide), split in their middle.
  EXPECT_EQ(brickXs(volume + "window: {level: 232, width: 64}\n"), (Xs{{0, 114}, {114, 128}}));
}

TEST(SortFirstPlan, TilesDealtToRenderersAndRoutedByCompositorRendererModM) {
  SortFirstPlan plan(true, 2);
  Workers w = twoByTwo();
  proto::FrameParams p = sized(64, 48);
  p.frame = 0;
  plan.fill(p, w);
  ASSERT_EQ(p.mode(), proto::FrameMode::SortFirst);
  const auto& tiles = p.sortFirst()->tiles;
  ASSERT_EQ(tiles.size(), 4u);
  long long area = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    EXPECT_EQ(tiles[i].renderer, w.renderers[i % 2]);
    EXPECT_EQ(tiles[i].compositor, w.compositors[i % 2].rank);
    area += tiles[i].tile.area();
  }
  EXPECT_EQ(area, 64 * 48);
  EXPECT_EQ(p.regions.size(), 2u);
}

TEST(SortFirstPlan, CostsOfAFullyReportedFrameRebalanceTheTiles) {
  SortFirstPlan plan(true, 1);
  Workers w{{0, 1}, {{0, ""}}};
  proto::FrameParams p0 = sized(64, 48);
  p0.frame = 0;
  plan.fill(p0, w);
  ASSERT_EQ(p0.sortFirst()->tiles.size(), 2u);
  for (uint32_t r : {0u, 1u}) {
    proto::StageStats s;
    s.frame = 0;
    s.rank = r;
    s.tile_ms = {r == 0 ? 100.0 : 1.0};  // renderer 0's tile is expensive
    plan.stats(s, w);
  }
  proto::FrameParams p1 = sized(64, 48);
  p1.frame = 1;
  plan.fill(p1, w);
  ASSERT_EQ(p1.sortFirst()->tiles.size(), 2u);
  EXPECT_LT(p1.sortFirst()->tiles[0].tile.area(), p0.sortFirst()->tiles[0].tile.area())
      << "the expensive tile should shrink";
  // A reduced frame keeps the balance at its own size: its tiles cover exactly its pixels.
  proto::FrameParams half = sized(21, 16);
  half.frame = 2;
  plan.fill(half, w);
  ASSERT_EQ(half.sortFirst()->tiles.size(), 2u);
  EXPECT_LT(half.sortFirst()->tiles[0].tile.area(), 21 * 16 / 2);
  EXPECT_EQ(half.sortFirst()->tiles[0].tile.area() + half.sortFirst()->tiles[1].tile.area(), 21 * 16);
}


// A renderer's report that comes twice (a resent or stray Stats) counts once: the plans that
// heard it twice make the frames of the plans that heard it once.
TEST(SortLastPlan, ARepeatedReportCountsOnce) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 16, 1};
  auto bandsAfter = [&](int repeats) {
    SortLastPlan plan(summarizeVolume(scene), scene.tf, true);
    Workers w = twoByTwo();
    plan.reassign(w);
    proto::FrameParams issued = sized(64, 48);
    issued.frame = 3;
    plan.fill(issued, w);
    proto::StageStats s;
    s.frame = 3;
    s.rank = 0;
    s.active = {0, 0, 64, 8};
    for (int i = 0; i < repeats; ++i) plan.stats(s, w);
    s.rank = 2;
    s.active = {0, 30, 64, 18};
    plan.stats(s, w);
    proto::FrameParams p = sized(64, 48);
    p.frame = 4;
    plan.fill(p, w);
    std::vector<int> heights;
    for (const auto& r : p.regions) heights.push_back(r.region.h);
    return heights;
  };
  ASSERT_EQ(bandsAfter(1).size(), 2u);
  EXPECT_EQ(bandsAfter(10), bandsAfter(1));
}

TEST(SortFirstPlan, ARepeatedReportCountsOnce) {
  auto tilesAfter = [](int repeats) {
    SortFirstPlan plan(true, 1);
    Workers w{{0, 1}, {{0, ""}}};
    proto::FrameParams p0 = sized(64, 48);
    p0.frame = 0;
    plan.fill(p0, w);
    for (uint32_t r : {0u, 1u})
      for (int i = 0; i < (r == 0 ? repeats : 1); ++i) {
        proto::StageStats s;
        s.frame = 0;
        s.rank = r;
        s.tile_ms = {r == 0 ? 1.0 : 100.0};  // the renderer heard last has the expensive tile
        plan.stats(s, w);
      }
    proto::FrameParams p1 = sized(64, 48);
    p1.frame = 1;
    plan.fill(p1, w);
    std::vector<int> areas;
    for (const auto& t : p1.sortFirst()->tiles) areas.push_back(t.tile.area());
    return areas;
  };
  ASSERT_EQ(tilesAfter(1).size(), 2u);
  EXPECT_EQ(tilesAfter(2), tilesAfter(1));
}

}  // namespace
}  // namespace tessera::master
