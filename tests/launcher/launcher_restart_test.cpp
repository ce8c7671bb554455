// tessera-up's `restart:` policies with real processes (/bin/sh scripts in DIR): a child
// that dies is started again with the same plan, exit 0 is not a failure, `always`
// restarts anyway, crash loops and retry limits stop the farm (unless other replicas of the
// service run: then only that replica is given up), and nothing is restarted
// once the farm is stopping. Every wait inside a script is bounded by a count.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/launcher/launcher_fixture.h"

namespace tessera::launcher {
namespace {

using std::chrono::milliseconds;

class RestartTest : public LauncherTest {
 protected:
  void SetUp() override {
    LauncherTest::SetUp();
    restart_limits_.backoff = milliseconds(10);  // the policy, not the patience, is under test
  }
  // Writes DIR/<name>.sh; compose files run it as `sh ${DIR}/<name>.sh`.
  void script(const std::string& name, const std::string& body) {
    std::ofstream(dir_ / (name + ".sh")) << "DIR='" << dir_.string() << "'\n" << body;
  }
};

// Appends "<replica> <FOO>" to DIR/starts: the plan (replica number, environment) of each start.
constexpr const char* kLogStart = "echo \"$TESSERA_REPLICA $FOO\" >> \"$DIR/starts\"\n";
// Waits (at most 30 s) until DIR/starts has $1 lines.
constexpr const char* kWaitStarts =
    "for i in $(seq 600); do [ \"$(cat \"$DIR/starts\" 2>/dev/null | wc -l)\" -ge $1 ] && break; sleep 0.05; done\n";

TEST_F(RestartTest, DiedChildIsRestartedWithTheSamePlan) {
  // Replica 2 kills itself on its first start only.
  script("renderer", std::string(kLogStart) +
                         "if [ $TESSERA_REPLICA = 2 ] && [ ! -e \"$DIR/killed\" ]; then touch \"$DIR/killed\"; "
                         "kill -9 $$; fi\nexec sleep 30\n");
  script("display", std::string(kWaitStarts) + "echo done\n");
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', environment: {FOO: bar}, restart: on-failure, deploy: {replicas: 2}}
  display: {command: 'sh ${DIR}/display.sh 3'}
)");
  EXPECT_EQ(code, 0) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer-2 died (signal 9); restarting (restart: on-failure, attempt 1)"))
      << allLines();
  EXPECT_TRUE(hasLineStarting("tessera-up | renderer-2 restarted (pid ")) << allLines();
  auto starts = fileLines("starts");
  std::sort(starts.begin(), starts.end());
  EXPECT_EQ(starts, (std::vector<std::string>{"1 bar", "2 bar", "2 bar"}));
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-1 died")) << allLines();
}

TEST_F(RestartTest, OnFailureDoesNotRestartACleanExit) {
  // The display ends once the launcher has reaped the renderer (its pid is gone), so the
  // renderer's end has been judged before the farm stops.
  script("renderer", std::string(kLogStart) + "echo $$ > \"$DIR/r.pid\"\nexit 0\n");
  script("display", std::string(kWaitStarts) +
                        "for i in $(seq 600); do kill -0 $(cat \"$DIR/r.pid\") 2>/dev/null || break; sleep 0.05; done\n");
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: on-failure}
  display: {command: 'sh ${DIR}/display.sh 1'}
)");
  EXPECT_EQ(code, 0) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer finished")) << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer exited")) << allLines();
  EXPECT_EQ(fileLines("starts").size(), 1u);
}

TEST_F(RestartTest, AlwaysRestartsAfterExitZero) {
  script("renderer", std::string(kLogStart) + "[ $(wc -l < \"$DIR/starts\") -ge 3 ] && exec sleep 30\nexit 0\n");
  script("display", std::string(kWaitStarts));
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: always}
  display: {command: 'sh ${DIR}/display.sh 3'}
)");
  EXPECT_EQ(code, 0) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer exited (exit code 0); restarting (restart: always, attempt 1)"))
      << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer exited (exit code 0); restarting (restart: always, attempt 2)"))
      << allLines();
  EXPECT_EQ(fileLines("starts").size(), 3u);  // the third start lasts until the stop
}

TEST_F(RestartTest, CrashLoopStopsTheFarm) {
  restart_limits_.crash_loop = 3;
  script("renderer", std::string(kLogStart) + "exit 1\n");
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: unless-stopped}
  display: {command: sleep 30}
)");
  EXPECT_EQ(code, 1) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer died (exit code 1); giving up on it: crash loop: 3 deaths in a row, "
                      "each within 10000 ms of starting; stopping the farm"))
      << allLines();
  EXPECT_EQ(fileLines("starts").size(), 3u);
}

// One replica in a crash loop while the other runs (its host cannot reach the master, say):
// it is given up, the farm goes on; the display ends the run normally.
TEST_F(RestartTest, ACrashLoopingReplicaIsLeftOutWhileItsSiblingRuns) {
  restart_limits_.crash_loop = 3;
  script("renderer", std::string(kLogStart) + "[ $TESSERA_REPLICA = 1 ] && exit 1\nexec sleep 30\n");
  // Ends 3 s after replica 1's third start, time for the launcher to reap it and log its
  // verdict (bounded: 30 s).
  script("display", "for i in $(seq 600); do grep -q given \"$DIR/verdict\" 2>/dev/null && break; "
                    "[ \"$(grep -c '^1 ' \"$DIR/starts\" 2>/dev/null)\" -ge 3 ] && sleep 3 && echo given > \"$DIR/verdict\"; "
                    "sleep 0.05; done\n");
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: on-failure, deploy: {replicas: 2}}
  display: {command: 'sh ${DIR}/display.sh'}
)");
  EXPECT_EQ(code, 0) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer-1 died (exit code 1); giving up on it: crash loop: 3 deaths in a row, "
                      "each within 10000 ms of starting; the farm goes on with 1 other renderer replica"))
      << allLines();
  EXPECT_TRUE(hasLine("tessera-up | display finished; stopping the farm")) << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-2 died")) << allLines();
}

TEST_F(RestartTest, RetryLimitStopsTheFarm) {
  script("renderer", std::string(kLogStart) + "exit 4\n");
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: 'on-failure:2'}
  display: {command: sleep 30}
)");
  EXPECT_EQ(code, 1) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer died (exit code 4); giving up on it: restart limit reached "
                      "(restart: on-failure:2, 2 restarts); stopping the farm"))
      << allLines();
  EXPECT_EQ(fileLines("starts").size(), 3u);
}

TEST_F(RestartTest, NothingIsRestartedWhenTheLeaderFinishes) {
  // The stop's SIGTERM kills the renderers: a death, but the farm is stopping.
  script("renderer", std::string(kLogStart) + "exec sleep 30\n");
  script("display", std::string(kWaitStarts));
  const int code = run(R"(
services:
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: always, deploy: {replicas: 2}}
  display: {command: 'sh ${DIR}/display.sh 2'}
)");
  EXPECT_EQ(code, 0) << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-1 died")) << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer-2 died")) << allLines();
  EXPECT_EQ(fileLines("starts").size(), 2u);
}

TEST_F(RestartTest, APendingRestartIsCancelledByAFatalDeath) {
  restart_limits_.backoff = milliseconds(600000);  // the master's death comes first
  script("renderer", std::string(kLogStart) + "echo $$ > \"$DIR/r.pid\"\nkill -9 $$\n");
  // The master dies once the launcher has reaped the renderer: its restart is pending.
  script("master", std::string(kWaitStarts) +
                       "for i in $(seq 600); do kill -0 $(cat \"$DIR/r.pid\") 2>/dev/null || break; sleep 0.05; done\n"
                       "exit 3\n");
  const int code = run(R"(
services:
  master: {command: 'sh ${DIR}/master.sh 1'}
  renderer: {command: 'sh ${DIR}/renderer.sh', restart: on-failure}
  display: {command: sleep 30}
)");
  EXPECT_EQ(code, 1) << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer died (signal 9); restarting (restart: on-failure, attempt 1)"))
      << allLines();
  EXPECT_TRUE(hasLine("tessera-up | master stopped with an error (exit code 3; its message is above): the farm cannot continue "
                      "without it; stopping"))
      << allLines();
  EXPECT_TRUE(hasLine("tessera-up | renderer will not be restarted: the farm is stopping")) << allLines();
  EXPECT_FALSE(hasLineStarting("tessera-up | renderer restarted")) << allLines();
  EXPECT_EQ(fileLines("starts").size(), 1u);
}

}  // namespace
}  // namespace tessera::launcher
