// What tessera-up does when a child of a service with a `restart:` policy ends: start it
// again after a growing backoff, or give up (retry limit, crash loop). Pure, no processes.
#pragma once
#include <chrono>
#include <string>

#include "master/launcher/compose.h"

namespace tessera::launcher {

struct RestartLimits {
  // The first restart in a row waits `backoff`, each further one twice as long, at most
  // `backoff_max`.
  std::chrono::milliseconds backoff{500};
  std::chrono::milliseconds backoff_max{8000};
  // A death sooner than this after the start is "rapid"; a longer run ends the streak.
  std::chrono::milliseconds stable_run{10000};
  // This many rapid deaths in a row is a crash loop: give up (and stop the farm).
  int crash_loop = 5;
};

// One child's restarts so far.
struct RestartHistory {
  int restarts = 0;        // all of them: attempt numbers, on-failure:N
  int rapid_failures = 0;  // deaths in a row, each within stable_run of its start
};

struct RestartVerdict {
  enum class Kind { None, Restart, GiveUp };  // None: the policy does not restart this end
  Kind kind = Kind::None;
  std::chrono::milliseconds delay{0};
  int attempt = 0;     // Restart: 1 for the first restart of this child
  std::string reason;  // GiveUp: why, for the log
};

// `status` is the waitpid status, `ran_for` how long the child ran. Updates `history`.
RestartVerdict judgeEnd(const RestartPolicy& policy, const RestartLimits& limits, RestartHistory& history,
                        int status, std::chrono::milliseconds ran_for);

}  // namespace tessera::launcher
