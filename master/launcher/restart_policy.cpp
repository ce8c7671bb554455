// Compose `restart:` values and what they mean for a child that ended. See compose.h.
#include <sys/wait.h>

#include "master/launcher/compose.h"

namespace tessera::launcher {

RestartPolicy parseRestartPolicy(const std::string& value, const std::string& where) {
  const auto bad = [&](const std::string& why) -> RestartPolicy {
    throw ComposeError(where + ": " + why + " (expected no, on-failure, on-failure:N, always or unless-stopped)");
  };
  if (value == "no") return {};
  if (value == "always") return {RestartPolicy::Mode::Always, 0};
  if (value == "unless-stopped") return {RestartPolicy::Mode::UnlessStopped, 0};
  if (value == "on-failure") return {RestartPolicy::Mode::OnFailure, 0};
  if (value.rfind("on-failure:", 0) != 0) return bad("unknown value \"" + value + "\"");
  const std::string n = value.substr(11);
  if (n.empty() || n.size() > 6 || n.find_first_not_of("0123456789") != std::string::npos) {
    return bad("\"" + value + "\": the retry count must be a number");
  }
  return {RestartPolicy::Mode::OnFailure, std::stoi(n)};
}

bool RestartPolicy::restartsAfter(int status) const {
  switch (mode) {
    case Mode::No: return false;
    case Mode::OnFailure: return !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    case Mode::Always:
    case Mode::UnlessStopped: return true;
  }
  return false;
}

std::string RestartPolicy::text() const {
  switch (mode) {
    case Mode::No: return "no";
    case Mode::OnFailure: return max_retries > 0 ? "on-failure:" + std::to_string(max_retries) : "on-failure";
    case Mode::Always: return "always";
    case Mode::UnlessStopped: return "unless-stopped";
  }
  return "?";
}

}  // namespace tessera::launcher
