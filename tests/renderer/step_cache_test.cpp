// The renderer's step cache counts what the render path waited for: a step the prefetch
// thread was still reading when the frame wanted it is a miss, and the wait is its load
// time (they were counted as a hit read in no time).
#include "renderer/step_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <thread>

#include "common/clock.h"
#include "tests/common/temp_dir.h"

namespace tessera::renderer {
namespace {

using namespace std::chrono_literals;

TEST(StepCache, AFrameThatWaitsForThePrefetchOfItsStepCountsAMissAndItsWait) {
  const Scene scene = parseScene("volume:\n  generator: {name: moving-blobs, size: 64, steps: 4}\n", ".", "s.yaml");
  StepCache cache(scene, BackendKind::Cpu, 1ull << 30);
  // The test holds the prefetch of a step (of `held`) until it lets it go.
  std::mutex mu;
  std::condition_variable cv;
  int held = -1, reading = -1;
  cache.before_prefetch = [&](int step) {
    std::unique_lock lock(mu);
    reading = step;
    cv.notify_all();
    cv.wait(lock, [&] { return held != step; });
  };
  auto hold = [&](int step) {
    std::lock_guard lock(mu);
    held = step;
  };
  auto awaitReading = [&](int step) {
    std::unique_lock lock(mu);
    return cv.wait_for(lock, 10s, [&] { return reading == step; });
  };
  auto release = [&] {
    std::lock_guard lock(mu);
    held = -1;
    cv.notify_all();
  };
  const VoxelBox box{{0, 0, 0}, {64, 64, 64}};
  ASSERT_TRUE(cache.get(box, 0).volume);
  EXPECT_EQ(cache.take().misses, 1u);
  // Step 1's prefetch is in progress when the frame asks for it: the frame waits for it.
  hold(1);
  cache.prefetch({1});
  ASSERT_TRUE(awaitReading(1));
  const auto t0 = Clock::now();
  auto frame = std::async(std::launch::async, [&] { return cache.get(box, 1); });
  std::this_thread::sleep_for(200ms);  // the frame reaches its wait
  release();
  ASSERT_EQ(frame.get().step, 1);
  const double waited = msSince(t0);
  StepCacheStats s = cache.take();
  EXPECT_EQ(s.hits, 0u);
  EXPECT_EQ(s.misses, 2u);
  EXPECT_GE(s.load_ms, 150) << "the frame waited " << waited << " ms";
  EXPECT_LE(s.load_ms, waited);
  // A step the prefetch read before the frame asked is a hit, read in no time.
  cache.prefetch({2});
  for (int i = 0; i < 500 && cache.take().prefetch_ms == 0; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(cache.get(box, 2).step, 2);
  s = cache.take();
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.load_ms, 0);
  // The bricks move while the prefetch reads a step of the old window: the frame does not
  // wait for that read (held until the frame has its step), it reads its own window.
  hold(3);
  cache.prefetch({3});
  ASSERT_TRUE(awaitReading(3));
  auto moved = std::async(std::launch::async, [&] { return cache.get(VoxelBox{{0, 0, 0}, {8, 8, 8}}, 3); });
  const bool waited_for_old = moved.wait_for(10s) != std::future_status::ready;
  release();
  EXPECT_FALSE(waited_for_old) << "waited for the old window's step";
  const HeldStep small = moved.get();
  ASSERT_EQ(small.step, 3);
  EXPECT_EQ(small.volume->dims, (std::array<int, 3>{8, 8, 8}));
}

// A budget under one step (TESSERA_CACHE_MB=0, or a step bigger than the cache) evicted the
// last good step when the next was asked for, so a bad step had nothing to show and the
// renderer failed every frame (found by review). It is held whatever the budget.
TEST(StepCache, ABadStepShowsTheLastGoodOneWhateverTheBudget) {
  tessera::test::TempDir dir("step_cache_budget");
  std::vector<uint8_t> voxels(16 * 16 * 16, 7);
  dir.write("t0.raw", voxels.data(), voxels.size());
  dir.write("t1.raw", voxels.data(), voxels.size());
  dir.write("t2.raw", voxels.data(), 100);  // short
  const Scene scene = parseScene("volume: {series: [t0.raw, t1.raw, t2.raw], dims: [16, 16, 16], type: uint8, "
                                 "range: [0, 255]}\n", dir.path.string(), "s.yaml");
  StepCache cache(scene, BackendKind::Cpu, 0);
  const VoxelBox box{{0, 0, 0}, {16, 16, 16}};
  ASSERT_TRUE(cache.get(box, 0).volume);
  ASSERT_EQ(cache.get(box, 1).step, 1);
  for (int pass = 0; pass < 3; ++pass) {  // asked again, as a playing series does
    const HeldStep shown = cache.get(box, 2);
    ASSERT_TRUE(shown.volume) << "nothing to show for the bad step, pass " << pass;
    EXPECT_EQ(shown.step, 1);
  }
  EXPECT_EQ(cache.get(box, 0).step, 0);
  EXPECT_EQ(cache.take().bad_steps, 3u);
}

}  // namespace
}  // namespace tessera::renderer

namespace tessera::renderer {
namespace {

// A step that cannot be read shows the last good one, through the frame's colour window too.
TEST(StepCache, TheLastGoodStepShownForABadOneIsShownThroughTheFramesWindow) {
  tessera::test::TempDir dir("step_cache_window");
  std::vector<uint8_t> voxels(16 * 16 * 16);
  for (size_t i = 0; i < voxels.size(); ++i) voxels[i] = (uint8_t)(i * 37 % 251);
  dir.write("t0.raw", voxels.data(), voxels.size());
  dir.write("t1.raw", voxels.data(), 100);  // short
  const Scene scene = parseScene("volume: {series: [t0.raw, t1.raw], dims: [16, 16, 16], type: uint8, range: [0, 255]}\n",
                                 dir.path.string(), "s.yaml");
  StepCache cache(scene, BackendKind::Cpu, 1ull << 30);
  const VoxelBox box{{0, 0, 0}, {16, 16, 16}};
  ASSERT_TRUE(cache.get(box, 0).volume);
  const ColorWindow w{0.3, 0.4};
  const HeldStep shown = cache.get(box, 1, w);
  ASSERT_EQ(shown.step, 0);
  RenderOptions ro;
  ro.threads = 1;
  const Brick whole{{0, 0, 0}, {16, 16, 16}};
  const ImageF got = shown.caster->render(scene.camera, 32, 32, whole, ro);
  const ImageF want = makeVolumeBackend(BackendKind::Cpu, shown.volume, windowed(scene.tf, w))->render(scene.camera, 32, 32, whole, ro);
  const ImageF plain = makeVolumeBackend(BackendKind::Cpu, shown.volume, scene.tf)->render(scene.camera, 32, 32, whole, ro);
  EXPECT_EQ(got.px, want.px);
  EXPECT_NE(got.px, plain.px) << "the window changed nothing";
}

}  // namespace
}  // namespace tessera::renderer
