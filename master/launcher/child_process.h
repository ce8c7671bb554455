// The launcher's process plumbing: the forked child's setup before exec, and the signal
// handlers that wake the supervisor (SIGCHLD) or ask it to stop (SIGINT/SIGTERM).
// Internal to tessera::launcher.
#pragma once
#include <signal.h>
#include <sys/types.h>

#include <utility>
#include <vector>

namespace tessera::launcher {

// Runs in the forked child: only async-signal-safe calls. Reports exec failure's errno
// through `status_fd` (closed on exec success by O_CLOEXEC, so the parent reads EOF).
[[noreturn]] void execChild(pid_t parent, const char* dir, const char* exe, char* const* argv,
                            char* const* envp, int out_fd, int err_fd, int status_fd);

// SIGINT/SIGTERM received since the last clearStopSignal() (0: none).
int pendingStopSignal();
void clearStopSignal();

// Installs the launcher's handlers for its lifetime and restores the previous ones.
class SignalScope {
 public:
  SignalScope(int wake_fd, bool handle_stop);
  ~SignalScope();
  SignalScope(const SignalScope&) = delete;
  SignalScope& operator=(const SignalScope&) = delete;
  static bool active();  // one is installed (launch() is running)

 private:
  void install(int signo, const struct sigaction& sa);
  std::vector<std::pair<int, struct sigaction>> saved_;
};

}  // namespace tessera::launcher
