#include "master/metrics.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace tessera::master {
namespace {

proto::StageStats stats(proto::Role role, uint32_t rank, uint64_t frame, double ms, uint32_t epoch = 0) {
  proto::StageStats s;
  s.epoch = epoch;
  s.role = role;
  s.rank = rank;
  s.frame = frame;
  s.work_ms = ms;
  s.bytes_raw = 100;
  s.active_pixels = 10;
  return s;
}

TEST(Metrics, SummaryTakesTheSlowestStageAndTheImbalance) {
  proto::FrameDone d;
  d.frame = 4;
  d.display_ms = 2;
  auto j = Metrics::summarize({stats(proto::Role::Renderer, 0, 4, 10), stats(proto::Role::Renderer, 1, 4, 30)},
                              {stats(proto::Role::Compositor, 0, 4, 5)}, d, 50);
  EXPECT_EQ(j["frame"], 4);
  EXPECT_DOUBLE_EQ(j["render_ms_max"].get<double>(), 30);
  EXPECT_DOUBLE_EQ(j["render_imbalance_time"].get<double>(), 1.5);
  EXPECT_EQ(j["render_bytes_raw"].get<uint64_t>(), 200u);
  EXPECT_EQ(j["composite_reports"].get<size_t>(), 1u);
  EXPECT_DOUBLE_EQ(j["latency_ms"].get<double>(), 50);
}

TEST(Metrics, AFrameOfReusedImagesHasNoRenderTime) {
  proto::FrameDone d;
  auto reused = stats(proto::Role::Renderer, 0, 0, 0.001);
  reused.images_reused = 1;
  auto j = Metrics::summarize({reused, reused}, {}, d, 5);
  EXPECT_FALSE(j["rerendered"].get<bool>());
  EXPECT_FALSE(j.contains("render_ms_max")) << j.dump();
  EXPECT_FALSE(j.contains("render_imbalance_time")) << j.dump();
  EXPECT_EQ(j["render_images_reused"], 2);
  auto made = stats(proto::Role::Renderer, 1, 0, 40);
  made.images_made = 1;  // one brick moved (a renderer failed): the frame was rendered
  j = Metrics::summarize({reused, made}, {}, d, 5);
  EXPECT_TRUE(j["rerendered"].get<bool>());
  EXPECT_DOUBLE_EQ(j["render_ms_max"].get<double>(), 40);
  EXPECT_EQ(j["render_images_made"], 1);
}

TEST(Metrics, ABinarySwapFrameShowsTheLongestWaitForAPartner) {
  proto::FrameDone d;
  auto r0 = stats(proto::Role::Renderer, 0, 0, 10), r1 = stats(proto::Role::Renderer, 1, 0, 30);
  r0.decode_ms = 2, r0.wait_ms = 21;  // r0 finished first and waited for r1's half
  r1.decode_ms = 3, r1.wait_ms = 0.5;
  auto j = Metrics::summarize({r0, r1}, {}, d, 5);
  EXPECT_DOUBLE_EQ(j["render_swap_ms_max"].get<double>(), 3);
  EXPECT_DOUBLE_EQ(j["render_swap_wait_ms_max"].get<double>(), 21);
  EXPECT_FALSE(Metrics::summarize({stats(proto::Role::Renderer, 0, 0, 10)}, {}, d, 5).contains("render_swap_wait_ms_max"))
      << "direct send has no swap";
}

TEST(Metrics, ATimeSeriesFrameShowsEachRenderersStepCacheByRank) {
  proto::FrameDone d;
  auto r1 = stats(proto::Role::Renderer, 1, 0, 10), r0 = stats(proto::Role::Renderer, 0, 0, 10);
  r1.step_hits = 9, r1.step_misses = 1, r1.bytes_read = 4096, r1.prefetch_ms = 30, r1.load_ms = 0;
  r0.step_hits = 8, r0.step_misses = 2, r0.bytes_read = 2048, r0.prefetch_ms = 12, r0.load_ms = 7;
  auto j = Metrics::summarize({r1, r0}, {}, d, 5);
  EXPECT_EQ(j["render_step_hits"], 17);
  EXPECT_DOUBLE_EQ(j["render_prefetch_ms_max"].get<double>(), 30);
  ASSERT_EQ(j["render_step_cache"].size(), 2u) << j.dump();
  EXPECT_EQ(j["render_step_cache"][0]["rank"], 0);
  EXPECT_EQ(j["render_step_cache"][0]["misses"], 2);
  EXPECT_DOUBLE_EQ(j["render_step_cache"][0]["load_ms"].get<double>(), 7);
  EXPECT_EQ(j["render_step_cache"][1]["bytes_read"], 4096);
  EXPECT_DOUBLE_EQ(j["render_step_cache"][1]["prefetch_ms"].get<double>(), 30);
  EXPECT_FALSE(Metrics::summarize({stats(proto::Role::Renderer, 0, 0, 10)}, {}, d, 5).contains("render_step_cache"))
      << "a volume without time has none";
}

TEST(Metrics, LineWrittenOnceDoneAndAllStatsAreInWithTheFaultCounters) {
  auto path = std::filesystem::temp_directory_path() / ("tessera_metrics_test_" + std::to_string(::getpid()) + ".jsonl");
  {
    Metrics m(path.string());
    m.issued(0, 2, 1, 1, FrameSpec{});
    m.stats(stats(proto::Role::Renderer, 0, 0, 10, 2));
    m.reassigned();
    m.reissued(3);
    m.refused();
    m.refused();
    proto::FrameDone d;
    d.frame = 0;
    m.done(d, 12, 5);
    EXPECT_EQ(m.pending(), 1u) << "the compositor's stats are missing";
    m.stats(stats(proto::Role::Compositor, 0, 0, 4, 2));
    EXPECT_EQ(m.pending(), 0u);
    EXPECT_EQ(m.framesDone(), 1u);
    m.stats(stats(proto::Role::Compositor, 0, 0, 4, 2));  // late duplicate: ignored
  }
  std::ifstream in(path);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  auto j = nlohmann::json::parse(line);
  EXPECT_EQ(j["epoch"], 2);
  EXPECT_EQ(j["master_dropped"], 5);
  EXPECT_EQ(j["reassignments"], 1);
  EXPECT_EQ(j["reissued_frames"], 3);
  EXPECT_EQ(j["refused_peers"], 2);
  EXPECT_FALSE(std::getline(in, line)) << "one line per frame";
  std::filesystem::remove(path);
}

// A member that repeats its Stats (or sends them for an earlier issue of the frame) counts
// once: it once grew the master's memory with every copy until the frame was written.
TEST(Metrics, RepeatedAndStaleStatsCountOnce) {
  auto path = std::filesystem::temp_directory_path() / ("tessera_metrics_repeat_" + std::to_string(::getpid()) + ".jsonl");
  {
    Metrics m(path.string());
    m.issued(0, 1, 2, 0, FrameSpec{});
    for (int i = 0; i < 1000; ++i) m.stats(stats(proto::Role::Renderer, 0, 0, 10 + i, 1));
    m.stats(stats(proto::Role::Renderer, 1, 0, 99, 0));  // an earlier issue's
    proto::FrameDone d;
    m.done(d, 12, 0);
    EXPECT_EQ(m.pending(), 1u) << "renderer 1 has not reported for this issue of the frame";
    m.stats(stats(proto::Role::Renderer, 1, 0, 7, 1));
    EXPECT_EQ(m.pending(), 0u);
  }
  std::ifstream in(path);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  auto j = nlohmann::json::parse(line);
  EXPECT_EQ(j["render_reports"], 2);
  EXPECT_EQ(j["render_ms_max"], 1009) << "renderer 0's last report";
  std::filesystem::remove(path);
}

TEST(Metrics, FlushWritesDoneFramesWhoseStatsNeverCame) {
  Metrics m("");
  m.issued(0, 0, 2, 1, FrameSpec{});
  proto::FrameDone d;
  m.done(d, 1, 0);
  EXPECT_EQ(m.pending(), 1u);
  m.flushAll();
  EXPECT_EQ(m.pending(), 0u);
  EXPECT_EQ(m.framesDone(), 1u);
}

// A new-user finding: a run that failed to start wiped the last run's metrics.
TEST(Metrics, ARunThatWritesNoLineKeepsThePreviousFileAndLeavesNoneOfItsOwn) {
  const auto dir = std::filesystem::temp_directory_path() / ("tessera-metrics-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = (dir / "metrics.jsonl").string();
  { Metrics failed_start(path); }
  EXPECT_FALSE(std::filesystem::exists(path)) << "an empty metrics file was left behind";
  std::ofstream(path) << "{\"frame\":0}\n";
  { Metrics failed_start(path); }
  std::ifstream in(path);
  std::string line;
  EXPECT_TRUE(std::getline(in, line) && line == "{\"frame\":0}") << "the previous run's line is gone";
  {
    Metrics run(path);
    run.issued(0, 0, 0, 0, FrameSpec{});
    run.done(proto::FrameDone{}, 1, 0);
  }
  std::ifstream again(path);
  ASSERT_TRUE(std::getline(again, line));
  EXPECT_NE(line.find("\"latency_ms\""), std::string::npos) << "a run that writes replaces the file: " << line;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace tessera::master
