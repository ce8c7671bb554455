// The renderer's step cache counts what the render path waited for: a step the prefetch
// thread was still reading when the frame wanted it is a miss, and the wait is its load
// time (they were counted as a hit read in no time).
#include "renderer/step_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/clock.h"

namespace tessera::renderer {
namespace {

TEST(StepCache, AFrameThatWaitsForThePrefetchOfItsStepCountsAMissAndItsWait) {
  // moving-blobs at 192^3: generating one step takes tens of milliseconds.
  const Scene scene = parseScene("volume:\n  generator: {name: moving-blobs, size: 192, steps: 4}\n", ".", "s.yaml");
  StepCache cache(scene, BackendKind::Cpu, 1ull << 30);
  const VoxelBox box{{0, 0, 0}, {192, 192, 192}};
  ASSERT_TRUE(cache.get(box, 0).volume);
  StepCacheStats s = cache.take();
  EXPECT_EQ(s.misses, 1u);
  cache.prefetch({1});
  std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the prefetch thread is reading step 1
  const auto t0 = Clock::now();
  ASSERT_EQ(cache.get(box, 1).step, 1);
  const double waited = msSince(t0);
  s = cache.take();
  EXPECT_EQ(s.hits, 0u) << "waited " << waited << " ms";
  EXPECT_EQ(s.misses, 2u);
  EXPECT_GT(waited, 5) << "the step was ready: nothing to test";
  EXPECT_GE(s.load_ms, 0.8 * waited);
  // A step the prefetch read before the frame asked is a hit, read in no time.
  cache.prefetch({2});
  for (int i = 0; i < 200 && cache.take().prefetch_ms == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(cache.get(box, 2).step, 2);
  s = cache.take();
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.load_ms, 0);
  // The bricks move while the prefetch reads a step of the old window: the frame does not
  // wait for that read, it reads its own small window at once.
  cache.prefetch({3});
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const auto t1 = Clock::now();
  const HeldStep small = cache.get(VoxelBox{{0, 0, 0}, {8, 8, 8}}, 3);
  const double small_ms = msSince(t1);
  ASSERT_EQ(small.step, 3);
  EXPECT_EQ(small.volume->dims, (std::array<int, 3>{8, 8, 8}));
  EXPECT_LT(small_ms, waited / 2) << "waited for the old window's step";
}

}  // namespace
}  // namespace tessera::renderer
