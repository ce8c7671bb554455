// The farm under a real Slurm (tests/slurm/one_host_slurm.sh: munged, slurmctld and two
// slurmd nodes on this host, started and stopped by each test), submitted with the README's
// batch script (docs/tessera.sbatch) as a user would: its frames equal the one-process
// render, two farms at once never mix, a lost renderer is survived, a lost master ends the
// step with a message naming its task and node, and scancel leaves no process behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <regex>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

constexpr int kSkip = 77;  // one_host_slurm.sh: not root, or Slurm not installed

// Runs `script` (bash, with tests/slurm/jobs.sh sourced) inside a fresh one-host cluster of
// two nodes. The farm's binaries are on PATH; every farm writes exact frames (PAM).
CommandResult inCluster(const FarmDir& dir, const std::string& script, int timeout_s = 240) {
  std::ofstream(dir.path() / "scenario.sh") << "set -u\nsource " TESSERA_SOURCE_DIR "/tests/slurm/jobs.sh\n"
                                            << "export PATH=" TESSERA_BINARY_DIR "/bin:$PATH TESSERA_PREMULTIPLIED=1 "
                                            << "TESSERA_WINDOW=off\n" << script;
  return runCommand(TESSERA_SOURCE_DIR "/tests/slurm/one_host_slurm.sh --nodes 2 -- bash " +
                        (dir.path() / "scenario.sh").string(),
                    timeout_s);
}

// A farm folder as a user has it: compose.yaml and a scene; submitted from there.
fs::path farmFolder(const FarmDir& dir, const std::string& name, int frames, int size = 40, int w = 97, int h = 83) {
  const fs::path folder = dir.path() / name;
  fs::create_directories(folder);
  fs::copy_file(TESSERA_SOURCE_DIR "/compose.yaml", folder / "compose.yaml");
  fs::rename(dir.writeScene(frames, size, w, h), folder / "scene.yaml");
  return folder;
}

// Shell text that submits the README's batch script from `folder` and sets $job.
std::string submit(const fs::path& folder, const std::string& env = "") {
  return "job=$(cd " + folder.string() + " && env TESSERA_SCENE=scene.yaml " + env +
         " sbatch --parsable --overcommit " TESSERA_SOURCE_DIR "/docs/tessera.sbatch)\n";
}

// ... an interactive farm (TESSERA_FRAMES=0: it runs until stopped), once it shows frame 0.
std::string submitInteractive(const fs::path& folder) {
  return submit(folder, "TESSERA_FRAMES=0") + "wait_file " + (folder / "out/frame_000000.png").string() +
         " 60 || exit 1\n";
}

Image8 frameIn(const fs::path& folder, int k) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06d.pam", k);
  return readPam((folder / "out" / name).string());
}

std::string logOf(const fs::path& folder) {
  std::string all;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.path().filename().string().rfind("tessera-", 0) != 0 || e.path().extension() != ".log") continue;
    std::ifstream in(e.path());
    all += std::string(std::istreambuf_iterator<char>(in), {});
  }
  return all;
}

#define SKIP_WITHOUT_SLURM(r) \
  if ((r).exit_code == kSkip) GTEST_SKIP() << (r).output

TEST(Slurm, TheReadmeBatchScriptRendersTheOrbitOfTheOneProcessRender) {
  FarmDir dir("slurm-orbit");
  const int frames = 3;
  const fs::path farm = farmFolder(dir, "farm", frames);
  const auto r = inCluster(dir, submit(farm, "TESSERA_FRAMES=" + std::to_string(frames)) + "wait_job $job 120\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("COMPLETED 0:0"), std::string::npos) << r.output << logOf(farm);
  const std::string log = logOf(farm);
  EXPECT_NE(log.find("tasks: master=0 renderer=1-2 compositor=3 display=4"), std::string::npos) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("master \\(task 0 on node[12]\\).*listening pub=tcp://127\\.0\\.0\\.1:")))
      << log;
  for (int k = 0; k < frames; ++k) {
    EXPECT_TRUE(dir.matches(frameIn(farm, k), dir.reference(farm / "scene.yaml", k), 1, "frame_" + std::to_string(k)));
  }
  EXPECT_FALSE(fs::exists(farm / ".tessera-slurm")) << "the run folder (and its keys) must go";
}

// docs/tessera-hetjob.sbatch: the display in component 0 (partition viz: node2), the rest in
// component 1 (partition compute: node1), two job steps that meet through the run folder.
TEST(Slurm, TheHeterogeneousJobScriptPutsTheDisplayOnTheVizNode) {
  FarmDir dir("slurm-het");
  const int frames = 3;
  const fs::path farm = farmFolder(dir, "farm", frames);
  const auto r = inCluster(dir, "job=$(cd " + farm.string() + " && env TESSERA_SCENE=scene.yaml TESSERA_FRAMES=3 "
                                    "sbatch --parsable --overcommit " TESSERA_SOURCE_DIR "/docs/tessera-hetjob.sbatch)\n"
                                    "wait_job $job 120\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("COMPLETED 0:0"), std::string::npos) << r.output << logOf(farm);
  const std::string log = logOf(farm);
  EXPECT_NE(log.find("tasks: display=0 | master=0 renderer=1-2 compositor=3"), std::string::npos) << log;
  EXPECT_NE(log.find("display (task 0 on node2)"), std::string::npos) << log;
  EXPECT_NE(log.find("master (task 0 on node1)"), std::string::npos) << log;
  EXPECT_NE(log.find("renderer-2 (task 2 on node1)"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(farm / ".tessera-slurm"));
  for (int k = 0; k < frames; ++k) {
    EXPECT_TRUE(dir.matches(frameIn(farm, k), dir.reference(farm / "scene.yaml", k), 1, "frame_" + std::to_string(k)));
  }
}

TEST(Slurm, TwoFarmsSubmittedAtOnceBothFinishWithoutCrossTalk) {
  FarmDir dir("slurm-two");
  const int frames = 4;
  const fs::path a = farmFolder(dir, "a", frames);
  const fs::path b = farmFolder(dir, "b", frames, 48, 80, 64);  // another picture: cross-talk would show
  const std::string env = "TESSERA_FRAMES=" + std::to_string(frames);
  const auto r = inCluster(dir, submit(a, env) + "ja=$job\n" + submit(b, env) +
                                    "echo \"a: $(wait_job $ja 120)\"; echo \"b: $(wait_job $job 120)\"\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("a: COMPLETED 0:0"), std::string::npos) << r.output << logOf(a);
  EXPECT_NE(r.output.find("b: COMPLETED 0:0"), std::string::npos) << r.output << logOf(b);
  for (const fs::path& farm : {a, b}) {
    const std::string log = logOf(farm);
    EXPECT_NE(log.find("refused_peers=0"), std::string::npos) << log;
    for (int k = 0; k < frames; ++k) {
      EXPECT_TRUE(dir.matches(frameIn(farm, k), dir.reference(farm / "scene.yaml", k), 1,
                              farm.filename().string() + "_frame_" + std::to_string(k)));
    }
    EXPECT_FALSE(fs::exists(farm / ".tessera-slurm"));
  }
}

// One renderer's task is killed (tessera-up --slurm-task: the task is gone for good), then
// the other renderer's process (its task restarts it): the step still completes.
TEST(Slurm, KilledRendererTasksAndProcessesAreSurvivedWithEveryFrame) {
  FarmDir dir("slurm-renderer");
  // Enough frames after the 12th for the second kill to land while the farm still runs: the
  // survivor renders this small volume at ~35 frames a second (40 frames were too few once).
  const int frames = 150;
  const fs::path farm = farmFolder(dir, "farm", frames, 64, 256, 256);
  const auto r = inCluster(dir, submit(farm, "TESSERA_FRAMES=150 TESSERA_IN_FLIGHT=1") +
                                    "wait_file " + (farm / "out/frame_000003.png").string() + " 60 || exit 1\n"
                                    "kill_task " + farm.string() + " renderer\n"
                                    "wait_file " + (farm / "out/frame_000012.png").string() + " 60 || exit 1\n"
                                    "kill_stage " + farm.string() + " tessera-rendere\n"
                                    "wait_job $job 120\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("killed the renderer task"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("killed tessera-rendere"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("COMPLETED 0:0"), std::string::npos) << r.output << logOf(farm);
  EXPECT_TRUE(std::regex_search(logOf(farm), std::regex("renderer-[12] \\(task [12] on node[12]\\) died \\(signal 9\\); "
                                                        "restarting"))) << logOf(farm);
  for (int k : {0, frames / 2, frames - 1}) {
    EXPECT_TRUE(dir.matches(frameIn(farm, k), dir.reference(farm / "scene.yaml", k), 1, "frame_" + std::to_string(k)));
  }
}

// The master or the display: the farm cannot go on without either.
class SlurmLoss : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(SlurmLoss, EndsTheStepWithinFiveSecondsNamingItsTaskAndNode) {
  const auto [service, comm] = GetParam();
  FarmDir dir(std::string("slurm-") + service);
  const fs::path farm = farmFolder(dir, "farm", 3);
  const auto r = inCluster(dir, submitInteractive(farm) +
                                    "start=$(date +%s.%N); kill_stage " + farm.string() + " " + comm + "\n"
                                    "state=$(wait_job $job 30); end=$(date +%s.%N)\n"
                                    "echo \"state $state after $(awk \"BEGIN{print $end - $start}\") s\"\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  const std::string out = r.output;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("state ([A-Z]+) ([0-9:]+) after ([0-9.]+) s"))) << out;
  EXPECT_NE(m[1], "COMPLETED") << "a farm without its " << service << " must not look successful";
  EXPECT_NE(m[2], "0:0");
  EXPECT_LE(std::stod(m[3]), 5.0) << "the step must end within 5 s of losing the " << service;
  std::cout << "the job ended " << m[3] << " s after the " << service << " was killed\n";
  const std::string task = std::string(service) == "master" ? "0" : "4";
  EXPECT_TRUE(std::regex_search(logOf(farm), std::regex(std::string(service) + " \\(task " + task +
                                                        " on node[12]\\) died \\(signal 9\\)")))
      << logOf(farm);
  EXPECT_FALSE(fs::exists(farm / ".tessera-slurm"));
}

INSTANTIATE_TEST_SUITE_P(Slurm, SlurmLoss,
                         ::testing::Values(std::pair{"master", "tessera-master"}, std::pair{"display", "tessera-display"}),
                         [](const auto& p) { return std::string(p.param.first); });

TEST(Slurm, ScancelLeavesNoFarmProcessBehindWithinTenSeconds) {
  FarmDir dir("slurm-scancel");
  const fs::path farm = farmFolder(dir, "farm", 3);
  const auto r = inCluster(dir, submitInteractive(farm) +
                                    "echo \"running: $(farm_pids " + farm.string() + ")\"\n"
                                    "start=$(date +%s%N); scancel $job; end=$((SECONDS + 10)); left=x\n"
                                    "while [ $SECONDS -lt $end ]; do left=$(farm_pids " + farm.string() + "); [ -z \"$left\" ] && break; sleep 0.1; done\n"
                                    "echo \"left: [$left] after $(( ($(date +%s%N) - start) / 1000000 )) ms\"\n");
  SKIP_WITHOUT_SLURM(r);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("running: [0-9]+ [0-9]+ [0-9]+ [0-9]+ [0-9]+ [0-9]+ [0-9]+"))) << r.output;
  EXPECT_NE(r.output.find("left: []"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(farm / ".tessera-slurm")) << "the run folder (and its keys) must go";
  std::cout << r.output.substr(r.output.find("left: ")) << "\n";
}

}  // namespace
}  // namespace tessera::test
