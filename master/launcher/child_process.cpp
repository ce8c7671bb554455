// Forked-child setup and the launcher's signal handlers. See child_process.h.
#include "master/launcher/child_process.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cerrno>

namespace tessera::launcher {
namespace {

volatile sig_atomic_t g_signal = 0;
int g_wake_fd = -1;

void onSignal(int signo) {
  if (signo != SIGCHLD) g_signal = signo;
  const int saved = errno;
  const char c = 1;
  [[maybe_unused]] ssize_t n = ::write(g_wake_fd, &c, 1);  // full pipe: already awake
  errno = saved;
}

}  // namespace

[[noreturn]] void execChild(pid_t parent, const char* dir, const char* exe, char* const* argv,
                            char* const* envp, int out_fd, int err_fd, int status_fd) {
  setpgid(0, 0);  // own group: Ctrl-C reaches only the launcher, which stops whole groups
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (getppid() != parent) _exit(126);  // the launcher died before prctl took effect
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;  // SIG_IGN (SIGPIPE) would otherwise survive exec
  for (int s : {SIGINT, SIGTERM, SIGCHLD, SIGPIPE, SIGQUIT, SIGHUP}) sigaction(s, &dfl, nullptr);
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  const int devnull = open("/dev/null", O_RDONLY | O_CLOEXEC);  // a background group must not read the tty
  if (devnull >= 0) dup2(devnull, STDIN_FILENO);
  dup2(out_fd, STDOUT_FILENO);
  dup2(err_fd, STDERR_FILENO);
  int e = 0;
  if (chdir(dir) != 0) e = errno;
  if (e == 0) {
    execve(exe, argv, envp);
    e = errno;
  }
  [[maybe_unused]] ssize_t n = ::write(status_fd, &e, sizeof e);
  _exit(127);
}

int pendingStopSignal() { return g_signal; }
void clearStopSignal() { g_signal = 0; }

SignalScope::SignalScope(int wake_fd, bool handle_stop) {
  g_signal = 0;
  g_wake_fd = wake_fd;
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  install(SIGCHLD, sa);
  if (handle_stop) {
    install(SIGINT, sa);
    install(SIGTERM, sa);
  }
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;  // a closed stdout must not kill the supervisor
  install(SIGPIPE, ignore);
}

SignalScope::~SignalScope() {
  for (auto& [signo, old] : saved_) sigaction(signo, &old, nullptr);
  g_wake_fd = -1;
}

bool SignalScope::active() { return g_wake_fd >= 0; }

void SignalScope::install(int signo, const struct sigaction& sa) {
  struct sigaction old {};
  sigaction(signo, &sa, &old);
  saved_.emplace_back(signo, old);
}

}  // namespace tessera::launcher
