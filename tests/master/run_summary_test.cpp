// The run's progress and summary lines, from the metrics lines of its frames.
#include "master/run_summary.h"

#include <gtest/gtest.h>

namespace tessera::master {
namespace {

using namespace std::chrono_literals;

nlohmann::json frameLine(double render_ms, uint64_t bytes, uint64_t display_dropped) {
  return {{"render_ms_max", render_ms},      {"composite_ms_max", 2.5},  {"display_ms", 40.0},
          {"latency_ms", 300.0},             {"render_bytes_encoded", bytes}, {"composite_bytes_encoded", bytes},
          {"master_dropped", 1},             {"render_dropped", 0.0},   {"composite_dropped", 0.0},
          {"display_dropped", display_dropped}, {"strips_rejected", 0},  {"reassignments", 2}};
}

TEST(RunSummary, ProgressCountsDownAndTheSummarySaysWhatHappened) {
  const auto t0 = RunSummary::Clock::now();
  RunSummary run(5, t0);
  auto p = run.add(frameLine(100, 500000, 0), t0 + 1s);
  ASSERT_TRUE(p);
  EXPECT_EQ(*p, "frame 1 of 5 (20%), 0.00 fps");
  EXPECT_FALSE(run.add(frameLine(300, 500000, 0), t0 + 1500ms));  // within the interval
  p = run.add(frameLine(200, 500000, 0), t0 + 2s, 100ms);
  ASSERT_TRUE(p);
  EXPECT_EQ(*p, "frame 3 of 5 (60%), 2.00 fps, about 1 s left");
  EXPECT_FALSE(run.add(frameLine(250, 500000, 0), t0 + 2500ms));
  p = run.add(frameLine(150, 500000, 3), t0 + 3s);  // the last frame always reports
  ASSERT_TRUE(p);
  EXPECT_EQ(*p, "frame 5 of 5 (100%), 2.00 fps");
  EXPECT_EQ(run.line(t0 + 3s),
            "run summary: 5 frames in 3.0 s, 2.00 fps; median per frame: render 200 ms, composite 2.5 ms, "
            "display 40 ms, latency 300 ms; 1.00 MB per frame between stages; dropped 4 messages, "
            "0 strips rejected, 2 stages reassigned");
}

TEST(RunSummary, FramesThatReusedTheImageAreCountedNotTimed) {
  const auto t0 = RunSummary::Clock::now();
  RunSummary run(3, t0);
  run.add(frameLine(240, 1, 0), t0 + 1s);
  for (int k = 0; k < 2; ++k) {
    auto j = frameLine(0, 1, 0);
    j.erase("render_ms_max");
    run.add(j, t0 + 2s);
  }
  EXPECT_NE(run.line(t0 + 2s).find("render 240 ms (2 of 3 frames reused the image: the view did not change)"),
            std::string::npos)
      << run.line(t0 + 2s);
}

TEST(RunSummary, InteractiveRunsHaveNoEstimate) {
  const auto t0 = RunSummary::Clock::now();
  RunSummary run(0, t0);
  auto p = run.add(frameLine(100, 1, 0), t0 + 1s);
  ASSERT_TRUE(p);
  EXPECT_EQ(*p, "frame 1 done, 0.00 fps");
  EXPECT_NE(run.line(t0 + 2s).find("run summary: 1 frames in 2.0 s"), std::string::npos);
}

}  // namespace
}  // namespace tessera::master
