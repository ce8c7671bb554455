// tessera-up launcher with real processes (/bin/sh): replicas and their environment,
// prefixed output, stopping the farm on leader exit / death / signal, no orphans left.
// Restart policies: launcher_restart_test.cpp.
#include "master/launcher/launcher.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <thread>

#include "tests/launcher/launcher_fixture.h"

namespace tessera::launcher {
namespace {

using Clock = std::chrono::steady_clock;

// Each renderer records its pid and a background helper's pid, then waits for the stop.
constexpr const char* kRenderer = R"(
  renderer:
    command: >-
      sh -c 'echo $$$$ > "$$DIR/r$$TESSERA_REPLICA.pid";
      sleep 30 & echo $$! > "$$DIR/bg$$TESSERA_REPLICA.pid";
      echo "hello from $$TESSERA_SERVICE $$TESSERA_REPLICA"; printf part; sleep 0.2; echo ial;
      wait'
    environment: ["DIR=${DIR}"]
    deploy: {replicas: 3}
)";

TEST_F(LauncherTest, ReplicasRunPrefixedAndStopWhenTheLeaderFinishes) {
  const int code = run(std::string("services:") + kRenderer + R"(
  display:
    depends_on: [renderer]
    command: ["sh", "-c", "for i in 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20; do [ $$(ls ${DIR} | wc -l) -ge 6 ] && break; sleep 0.1; done; sleep 0.6; echo done"]
)");
  EXPECT_EQ(code, 0) << allLines();
  for (int r = 1; r <= 3; ++r) {
    EXPECT_TRUE(std::filesystem::exists(dir_ / ("r" + std::to_string(r) + ".pid"))) << r;
    EXPECT_TRUE(hasLine("renderer-" + std::to_string(r) + " | hello from renderer " + std::to_string(r)))
        << allLines();
    // A partial write followed by the rest is one line, not two.
    EXPECT_TRUE(hasLine("renderer-" + std::to_string(r) + " | partial")) << allLines();
  }
  EXPECT_TRUE(hasLine("display | done")) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | display finished; stopping the farm")) << allLines();
  const auto pids = recordedPids();
  EXPECT_EQ(pids.size(), 6u);  // 3 renderers + 3 background helpers
  for (pid_t pid : pids) EXPECT_FALSE(alive(pid)) << "orphan pid " << pid;
  // sh stops on SIGTERM at once: the grace period is never used up.
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-1 did not stop")) << allLines();
}

// A service without a restart policy (the master) is one the farm cannot do without,
// even while others would be restarted.
TEST_F(LauncherTest, KilledChildStopsTheFarmAndIsNamed) {
  const int code = run(R"(
services:
  master:
    command: sh -c 'echo $$$$ > ${DIR}/m.pid; for i in $$(seq 400); do [ $$(ls ${DIR} | wc -l) -ge 3 ] && break; sleep 0.05; done; kill -9 $$$$'
  renderer:
    command: sh -c 'echo $$$$ > ${DIR}/r$$TESSERA_REPLICA.pid; exec sleep 30'
    restart: on-failure
    deploy: {replicas: 2}
  display:
    command: sh -c 'exec sleep 30'
)");
  EXPECT_EQ(code, 1) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | master died (signal 9): the farm cannot continue without it; stopping"))
      << allLines();
  // The renderers ended by the stop are not restarted.
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-1 died")) << allLines();
  const auto pids = recordedPids();
  EXPECT_EQ(pids.size(), 3u);
  for (pid_t pid : pids) EXPECT_FALSE(alive(pid)) << "orphan pid " << pid;
}

TEST_F(LauncherTest, StubbornChildIsKilledAfterTheGracePeriod) {
  const int code = run(R"(
services:
  stubborn:
    command: sh -c 'trap "" TERM; echo $$$$ > ${DIR}/s.pid; while true; do sleep 0.05; done'
  display:
    command: sh -c 'sleep 0.3'
)", std::chrono::milliseconds(400));
  EXPECT_EQ(code, 0) << allLines();
  const size_t finished = indexOf("tessera-up | display finished; stopping the farm");
  const size_t killed = indexOf("tessera-up | stubborn did not stop in time; sending SIGKILL");
  EXPECT_LT(finished, lines_.size()) << allLines();
  EXPECT_LT(killed, lines_.size()) << allLines();
  EXPECT_LT(finished, killed) << allLines();
  for (pid_t pid : recordedPids()) EXPECT_FALSE(alive(pid)) << "orphan pid " << pid;
}

TEST_F(LauncherTest, NonLeaderExitingIsAFailure) {
  const int code = run(R"(
services:
  master: {command: sh -c 'exit 3'}
  display: {command: sleep 30}
)");
  EXPECT_EQ(code, 1);
  EXPECT_TRUE(hasLine("tessera-up | master stopped with an error (exit code 3; its message is above): the farm cannot continue "
                      "without it; stopping"))
      << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | display did not stop")) << allLines();
}

TEST_F(LauncherTest, NonLeaderFinishingCleanlyLetsTheLeaderFinish) {
  // Stages end on the master's Shutdown in any order: only the leader's exit ends the farm.
  EXPECT_EQ(run("services: {master: {command: 'true'}, display: {command: sh -c 'sleep 0.4; echo done'}}"), 0);
  EXPECT_TRUE(hasLine("tessera-up | master finished")) << allLines();
  EXPECT_TRUE(hasLine("display | done")) << allLines();  // it was not stopped early
  EXPECT_LT(indexOf("tessera-up | master finished"), indexOf("tessera-up | display finished; stopping the farm"))
      << allLines();
}

TEST_F(LauncherTest, WithoutLeaderTheFarmEndsWhenAllFinish) {
  EXPECT_EQ(run("services: {a: {command: 'true'}, b: {command: sh -c 'sleep 0.2; echo b', deploy: {replicas: 2}}}"), 0);
  EXPECT_TRUE(hasLine("b-2 | b")) << allLines();
}

TEST_F(LauncherTest, MissingCommandStartsNothing) {
  LaunchOptions options;
  options.handle_signals = false;
  options.output = [](std::string_view) {};
  const auto p = project("services: {a: {command: 'sh -c \"echo $$$$ > ${DIR}/a.pid\"'}, b: {command: no-such-tessera-binary}}");
  EXPECT_THROW(launch(p, options), LaunchError);
  EXPECT_TRUE(recordedPids().empty());
}

TEST_F(LauncherTest, ImagePathFallsBackToPath) {
  const auto plan = planProcesses(project("services: {a: {command: /usr/local/bin/no-such-dir/sh -c true}}"), {});
  ASSERT_EQ(plan.size(), 1u);
  EXPECT_EQ(std::filesystem::path(plan[0].executable).filename(), "sh");
  EXPECT_NE(plan[0].note.find("does not exist here"), std::string::npos);
  EXPECT_EQ(plan[0].environment.at("TESSERA_SERVICE"), "a");
  EXPECT_EQ(plan[0].environment.at("TESSERA_REPLICA"), "1");
}

// --launch-with: the wrapper runs each process; it sees the stage's command and identity.
TEST_F(LauncherTest, LaunchWithWrapsEveryProcess) {
  LaunchOptions options;
  options.handle_signals = false;
  options.output = [this](std::string_view line) { lines_.emplace_back(line); };
  options.launch_with = {"sh", "-c", "echo via-wrapper $TESSERA_SERVICE-$TESSERA_REPLICA; exec \"$@\"", "wrap"};
  const auto p = project("services: {a: {command: echo hello, deploy: {replicas: 2}}}");
  const auto plan = planProcesses(p, options);
  ASSERT_EQ(plan.size(), 2u);
  EXPECT_EQ(std::filesystem::path(plan[0].executable).filename(), "sh");
  EXPECT_EQ(std::filesystem::path(plan[0].argv.at(4)).filename(), "echo");
  EXPECT_EQ(launch(p, options), 0);
  EXPECT_TRUE(hasLine("a-2 | via-wrapper a-2")) << allLines();
  EXPECT_TRUE(hasLine("a-1 | hello")) << allLines();
}

// The real binary: SIGTERM to tessera-up stops the farm with exit code 143.
TEST_F(LauncherTest, BinaryStopsOnSigterm) {
  const std::string binary = TESSERA_BINARY_DIR "/bin/tessera-up";
  if (access(binary.c_str(), X_OK) != 0) GTEST_SKIP() << binary << " not built";
  std::ofstream(dir_ / "compose.yaml") << std::string("services:") + kRenderer;
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string file = (dir_ / "compose.yaml").string();
    const std::string env = "DIR=" + dir_.string();
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    execl(binary.c_str(), binary.c_str(), file.c_str(), "--env", env.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (recordedPids().size() < 6 && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(recordedPids().size(), 6u);
  kill(pid, SIGTERM);
  int status = 0;
  pid_t done = 0;
  while ((done = waitpid(pid, &status, WNOHANG)) == 0 && Clock::now() < deadline + std::chrono::seconds(3)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (done == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  ASSERT_EQ(done, pid) << "tessera-up did not exit after SIGTERM";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 143);
  for (pid_t p : recordedPids()) EXPECT_FALSE(alive(p)) << "orphan pid " << p;
}

}  // namespace
}  // namespace tessera::launcher
