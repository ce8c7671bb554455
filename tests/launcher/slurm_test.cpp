// tessera-up --slurm without a cluster: the task ranks of each service, the ports, and the
// whole --dry-run output byte for byte against tests/launcher/slurm_dry_run.expected (the
// real Slurm runs are in tests/integration/slurm_test.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "master/launcher/launcher.h"
#include "master/launcher/slurm.h"

namespace tessera::launcher {
namespace {

namespace fs = std::filesystem;

std::string run(const std::string& cmd, int* status = nullptr) {
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  size_t n;
  while (p && (n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int st = p ? pclose(p) : -1;
  if (status) *status = st;
  return out;
}

void replaceAll(std::string& s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
}

struct TempDir {
  TempDir() {
    char tmpl[] = "/tmp/tessera-slurm-dry-XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
};

// display, master and 3 renderers, listed out of start order.
ComposeProject threeRendererFarm() {
  ComposeOptions options;
  options.process_env = [](const std::string&) { return std::nullopt; };
  return parseCompose(
      "services:\n  display: {command: d, depends_on: [master]}\n  master: {command: m}\n"
      "  renderer: {command: r, deploy: {replicas: 3}, depends_on: [master]}\n",
      "/tmp", options, "compose.yaml");
}

TEST(SlurmPlan, ReplicasTakeConsecutiveRanksInStartOrder) {
  const auto project = threeRendererFarm();
  const auto steps = slurmSteps(project, 0);
  ASSERT_EQ(steps.size(), 1u);
  const auto& ranges = steps[0].ranges;
  ASSERT_EQ(ranges.size(), 3u);
  EXPECT_EQ(ranges[0].service, "master");
  EXPECT_EQ(ranges[0].first, 0);
  EXPECT_EQ(ranges[0].last, 0);
  int next = 1;
  for (size_t i = 1; i < ranges.size(); ++i) {
    EXPECT_EQ(ranges[i].first, next);
    next = ranges[i].last + 1;
  }
  EXPECT_EQ(next, 5);
  EXPECT_EQ(steps[0].tasks, 5);
  EXPECT_EQ(steps[0].het_group, -1);
}

TEST(SlurmPlan, AHeterogeneousJobRunsTheDisplayInComponentZeroAndTheRestInOne) {
  const auto project = threeRendererFarm();
  const auto steps = slurmSteps(project, 2);
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].het_group, 0);
  ASSERT_EQ(steps[0].ranges.size(), 1u);
  EXPECT_EQ(steps[0].ranges[0].service, "display");
  EXPECT_EQ(steps[0].tasks, 1);
  EXPECT_EQ(steps[1].het_group, 1);
  EXPECT_EQ(steps[1].tasks, 4);
  EXPECT_EQ(steps[1].ranges[0].first, 0) << "each step numbers its own tasks";
  EXPECT_THROW(slurmSteps(project, 3), LaunchError);
}

TEST(SlurmPlan, PortsDifferBetweenFarmsOfOneJobAndNeighbouringJobs) {
  for (int job = 1; job < 2000; ++job) {
    const int p = slurmFirstPort(std::to_string(job), 1);
    ASSERT_GE(p, 10000);
    ASSERT_LE(p + 100, 32768);  // below Linux's ephemeral ports
    ASSERT_EQ(p % 100, 0);
    EXPECT_NE(p, slurmFirstPort(std::to_string(job), 2));
    EXPECT_NE(p, slurmFirstPort(std::to_string(job + 1), 1));
  }
}

TEST(SlurmPlan, AFarmWithoutOneMasterAndOneDisplayIsRefusedAtOnce) {
  ComposeOptions options;
  options.process_env = [](const std::string&) { return std::nullopt; };
  const auto no_display = parseCompose("services:\n  master: {command: m}\n", "/tmp", options, "compose.yaml");
  try {
    slurmSteps(no_display, 0);
    ADD_FAILURE() << "no error";
  } catch (const LaunchError& e) {
    EXPECT_EQ(std::string(e.what()), "tessera-up --slurm needs exactly one 'display' service (none in the compose file)");
  }
}

TEST(SlurmPlan, SettingsSurviveTheRunFolderWhateverTheirCharacters) {
  const std::map<std::string, std::string> settings{
      {"TESSERA_OUT", "/data/it's \"here\"\\x"}, {"TESSERA_SCENE", "a b\tc\nd"}, {"TESSERA_RUN", "slurm-1-1"}};
  EXPECT_EQ(parseDotEnv(settingsText(settings), "settings.env"), settings);
}

class SlurmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (access(binary_.c_str(), X_OK) != 0) GTEST_SKIP() << binary_ << " not built";
  }
  // tessera-up in `dir` with a clean environment plus `env`; stdout and stderr.
  std::string tesseraUp(const fs::path& dir, const std::string& env, const std::string& args, int* status) {
    return run("cd " + dir.string() + " && env -i PATH=/usr/bin:/bin " + env + " " + binary_ + " " + args + " 2>&1",
               status);
  }
  const std::string binary_ = TESSERA_BINARY_DIR "/bin/tessera-up";
};

TEST_F(SlurmCli, DryRunPrintsTheMultiProgFileAndEachServicesEnvironmentByteForByte) {
  TempDir dir;
  const fs::path farm = dir.path / "farm";  // the project's name
  fs::create_directories(farm);
  fs::copy_file(TESSERA_SOURCE_DIR "/compose.yaml", farm / "compose.yaml");
  int status = 0;
  std::string out = run("cd " + farm.string() + " && env -i PATH=/usr/bin:/bin SLURM_JOB_ID=4242 " + binary_ +
                            " --slurm --dry-run compose.yaml --env TESSERA_RENDERERS=3 "
                            "--env TESSERA_COMPOSITORS=2 --env TESSERA_FRAMES=12 2>/dev/null",
                        &status);
  EXPECT_EQ(status, 0) << out;
  replaceAll(out, farm.string(), "@FARM@");
  replaceAll(out, TESSERA_BINARY_DIR "/bin", "@BIN@");
  std::ifstream in(TESSERA_SOURCE_DIR "/tests/launcher/slurm_dry_run.expected");
  std::stringstream expected;
  expected << in.rdbuf();
  EXPECT_EQ(out, expected.str()) << "to accept a deliberate change, write this output to the .expected file";
  EXPECT_FALSE(fs::exists(farm / ".tessera-slurm")) << "a dry run creates nothing";
}

TEST_F(SlurmCli, OutsideAnAllocationItSaysSo) {
  TempDir dir;
  int status = 0;
  const std::string out = tesseraUp(dir.path, "", "--slurm " TESSERA_SOURCE_DIR "/compose.yaml", &status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("runs inside a Slurm allocation (an sbatch script or salloc): SLURM_JOB_ID is not set"),
            std::string::npos) << out;
}

TEST_F(SlurmCli, TooSmallAnAllocationIsRefusedWithTheTaskCountToAskFor) {
  TempDir dir;
  int status = 0;
  const std::string out = tesseraUp(dir.path, "SLURM_JOB_ID=7 SLURM_NTASKS=3",
                                    "--slurm " TESSERA_SOURCE_DIR "/compose.yaml --env TESSERA_OUT=" +
                                        (dir.path / "out").string(),
                                    &status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("the farm needs 5 tasks in this allocation"), std::string::npos) << out;
  EXPECT_NE(out.find("but it has 3: sbatch --ntasks=5"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.path / ".tessera-slurm" / "7-1")) << "nothing left behind";
}

}  // namespace
}  // namespace tessera::launcher
