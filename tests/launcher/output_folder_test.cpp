// The output folder a run takes: an earlier run's frames go (a new-user finding: a shorter
// run left the old frame_000001... beside its own), everything else stays.
#include "master/launcher/output_lock.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <fstream>

namespace tessera::launcher {
namespace {

TEST(OutputFolder, AnEarlierRunsFramesAreRemovedAndNothingElse) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tessera-out-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const char* name : {"frame_000000.png", "frame_000001.pam", "frame_000002.png", "frame_1.png",
                           "frame_000003.png.bak", "metrics.jsonl", "head.raw"})
    std::ofstream(dir / name) << "x";
  EXPECT_EQ(removeOldFrames(dir), 3);
  for (const char* kept : {"frame_1.png", "frame_000003.png.bak", "metrics.jsonl", "head.raw"})
    EXPECT_TRUE(fs::exists(dir / kept)) << kept;
  EXPECT_FALSE(fs::exists(dir / "frame_000000.png"));
  EXPECT_EQ(removeOldFrames(dir / "missing"), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tessera::launcher
