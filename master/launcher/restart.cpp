// Restart decisions for tessera-up's children. See restart.h.
#include "master/launcher/restart.h"

#include <algorithm>

namespace tessera::launcher {

RestartVerdict judgeEnd(const RestartPolicy& policy, const RestartLimits& limits, RestartHistory& history,
                        int status, std::chrono::milliseconds ran_for) {
  RestartVerdict v;
  if (!policy.restartsAfter(status)) return v;
  history.rapid_failures = ran_for < limits.stable_run ? history.rapid_failures + 1 : 0;
  if (policy.max_retries > 0 && history.restarts >= policy.max_retries) {
    v.kind = RestartVerdict::Kind::GiveUp;
    v.reason = "restart limit reached (restart: " + policy.text() + ", " + std::to_string(history.restarts) +
               " restarts)";
    return v;
  }
  if (history.rapid_failures >= std::max(1, limits.crash_loop)) {
    v.kind = RestartVerdict::Kind::GiveUp;
    v.reason = "crash loop: " + std::to_string(history.rapid_failures) + " deaths in a row, each within " +
               std::to_string(limits.stable_run.count()) + " ms of starting";
    return v;
  }
  v.kind = RestartVerdict::Kind::Restart;
  v.attempt = ++history.restarts;
  // Doubling per rapid death in a row; the shift is bounded long before it could overflow.
  const int doublings = std::clamp(history.rapid_failures - 1, 0, 20);
  v.delay = std::min(limits.backoff * (int64_t{1} << doublings), std::max(limits.backoff, limits.backoff_max));
  return v;
}

}  // namespace tessera::launcher
