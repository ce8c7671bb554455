// The Compose `restart:` policy: parsing (values, errors naming the key), which ends it
// restarts, the growing backoff and the bounds (on-failure:N, crash loop).
#include "master/launcher/restart.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

namespace tessera::launcher {
namespace {

using std::chrono::milliseconds;
using Mode = RestartPolicy::Mode;
using Kind = RestartVerdict::Kind;

// waitpid statuses, built the way the kernel reports them.
constexpr int exitStatus(int code) { return (code & 0xff) << 8; }
constexpr int signalStatus(int signo) { return signo & 0x7f; }

ComposeProject parseProject(const std::string& yaml) {
  return parseCompose(yaml, "/nonexistent-dir", {}, "compose.yaml");
}

std::string errorOf(const std::string& yaml) {
  try {
    parseProject(yaml);
  } catch (const ComposeError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(RestartPolicy, ParsesEveryComposeValue) {
  const auto p = parseProject(R"(
services:
  a: {command: x}
  b: {command: x, restart: "no"}
  c: {command: x, restart: no}
  d: {command: x, restart: on-failure}
  e: {command: x, restart: "on-failure:3"}
  f: {command: x, restart: always}
  g: {command: x, restart: unless-stopped}
  h: {command: x, restart: "${POLICY:-always}"}
)");
  EXPECT_EQ(p.find("a")->restart, RestartPolicy{});  // default: no
  EXPECT_EQ(p.find("b")->restart.mode, Mode::No);
  EXPECT_EQ(p.find("c")->restart.mode, Mode::No);    // YAML's bare no is the string "no"
  EXPECT_EQ(p.find("d")->restart, (RestartPolicy{Mode::OnFailure, 0}));
  EXPECT_EQ(p.find("e")->restart, (RestartPolicy{Mode::OnFailure, 3}));
  EXPECT_EQ(p.find("f")->restart.mode, Mode::Always);
  EXPECT_EQ(p.find("g")->restart.mode, Mode::UnlessStopped);
  EXPECT_EQ(p.find("h")->restart.mode, Mode::Always);  // interpolated like any value
  EXPECT_EQ(p.find("e")->restart.text(), "on-failure:3");
  EXPECT_EQ(p.find("g")->restart.text(), "unless-stopped");
}

TEST(RestartPolicy, BadValuesNameTheKey) {
  const std::string expected = " (expected no, on-failure, on-failure:N, always or unless-stopped)";
  EXPECT_EQ(errorOf("services: {r: {command: x, restart: sometimes}}"),
            "compose.yaml: services.r.restart: unknown value \"sometimes\"" + expected);
  EXPECT_EQ(errorOf("services: {r: {command: x, restart: 'on-failure:x'}}"),
            "compose.yaml: services.r.restart: \"on-failure:x\": the retry count must be a number" + expected);
  EXPECT_EQ(errorOf("services: {r: {command: x, restart: 'on-failure:'}}"),
            "compose.yaml: services.r.restart: \"on-failure:\": the retry count must be a number" + expected);
  EXPECT_EQ(errorOf("services: {r: {command: x, restart: on-failures}}"),
            "compose.yaml: services.r.restart: unknown value \"on-failures\"" + expected);
  EXPECT_EQ(errorOf("services: {r: {command: x, restart: [always]}}"),
            "compose.yaml: services.r.restart: expected a string");
}

TEST(RestartPolicy, WhichEndsRestart) {
  const RestartPolicy no{}, on_failure{Mode::OnFailure, 0}, always{Mode::Always, 0}, unless{Mode::UnlessStopped, 0};
  for (int status : {exitStatus(0), exitStatus(1), signalStatus(SIGKILL)}) EXPECT_FALSE(no.restartsAfter(status));
  EXPECT_FALSE(on_failure.restartsAfter(exitStatus(0)));
  EXPECT_TRUE(on_failure.restartsAfter(exitStatus(2)));
  EXPECT_TRUE(on_failure.restartsAfter(signalStatus(SIGKILL)));
  EXPECT_TRUE(on_failure.restartsAfter(signalStatus(SIGSEGV)));
  for (int status : {exitStatus(0), exitStatus(1), signalStatus(SIGKILL)}) {
    EXPECT_TRUE(always.restartsAfter(status));
    EXPECT_TRUE(unless.restartsAfter(status));
  }
}

RestartLimits limits() {
  RestartLimits l;
  l.backoff = milliseconds(100);
  l.backoff_max = milliseconds(350);
  l.stable_run = milliseconds(1000);
  l.crash_loop = 4;
  return l;
}

TEST(RestartDecision, BackoffGrowsWithRapidDeathsAndIsBounded) {
  const RestartPolicy policy{Mode::OnFailure, 0};
  RestartHistory h;
  std::vector<int64_t> delays, attempts;
  for (int i = 0; i < 3; ++i) {
    const auto v = judgeEnd(policy, limits(), h, signalStatus(SIGKILL), milliseconds(10));
    ASSERT_EQ(v.kind, Kind::Restart) << i;
    delays.push_back(v.delay.count());
    attempts.push_back(v.attempt);
  }
  EXPECT_EQ(delays, (std::vector<int64_t>{100, 200, 350}));  // doubling, capped at backoff_max
  EXPECT_EQ(attempts, (std::vector<int64_t>{1, 2, 3}));
  // The 4th rapid death in a row is a crash loop.
  const auto v = judgeEnd(policy, limits(), h, signalStatus(SIGKILL), milliseconds(10));
  EXPECT_EQ(v.kind, Kind::GiveUp);
  EXPECT_EQ(v.reason, "crash loop: 4 deaths in a row, each within 1000 ms of starting");
}

TEST(RestartDecision, ALongRunEndsTheStreak) {
  const RestartPolicy policy{Mode::Always, 0};
  RestartHistory h;
  for (int i = 0; i < 3; ++i) judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(10));
  const auto v = judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(5000));
  EXPECT_EQ(v.kind, Kind::Restart);
  EXPECT_EQ(v.delay, milliseconds(100));  // back to the first backoff
  EXPECT_EQ(v.attempt, 4);                // attempts keep counting
  EXPECT_EQ(judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(10)).kind, Kind::Restart);
}

TEST(RestartDecision, OnFailureWithRetryLimit) {
  const RestartPolicy policy{Mode::OnFailure, 2};
  RestartHistory h;
  EXPECT_EQ(judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(5000)).kind, Kind::Restart);
  EXPECT_EQ(judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(5000)).kind, Kind::Restart);
  const auto v = judgeEnd(policy, limits(), h, exitStatus(1), milliseconds(5000));
  EXPECT_EQ(v.kind, Kind::GiveUp);
  EXPECT_EQ(v.reason, "restart limit reached (restart: on-failure:2, 2 restarts)");
}

TEST(RestartDecision, EndsThePolicyDoesNotRestartChangeNothing) {
  RestartHistory h;
  EXPECT_EQ(judgeEnd({Mode::OnFailure, 0}, limits(), h, exitStatus(0), milliseconds(10)).kind, Kind::None);
  EXPECT_EQ(judgeEnd({Mode::No, 0}, limits(), h, signalStatus(SIGKILL), milliseconds(10)).kind, Kind::None);
  EXPECT_EQ(h.restarts, 0);
  EXPECT_EQ(h.rapid_failures, 0);
}

}  // namespace
}  // namespace tessera::launcher
