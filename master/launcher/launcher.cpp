// Supervises the farm's child processes: spawn in start order, forward prefixed output
// lines, restart children as their service's `restart:` policy says, and stop everything
// (SIGTERM, grace period, SIGKILL) on leader exit, signal or a death nothing restarts.
#include "master/launcher/launcher.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <optional>

#include "master/launcher/child_process.h"

extern char** environ;

namespace tessera::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kMaxLine = 64 * 1024;  // a longer run without '\n' is forwarded in pieces
constexpr auto kKillWait = std::chrono::seconds(2);  // after SIGKILL; the kernel is quick

struct Stream {
  int fd = -1;
  std::string buf;
};

struct Child {
  PlannedProcess plan;
  pid_t pid = -1;
  bool running = false;
  Stream streams[2];  // stdout, stderr: separate so partial lines never mix
  Clock::time_point started{};
  RestartHistory history;
  std::optional<Clock::time_point> restart_at;  // set while it waits out its backoff
};

std::string describe(int status) {
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "exit code " + std::to_string(WEXITSTATUS(status));
}

class Supervisor {
 public:
  Supervisor(const ComposeProject& project, const LaunchOptions& options)
      : project_(project), options_(options) {
    if (!options_.output) {
      options_.output = [](std::string_view line) {
        std::string s(line);
        s += '\n';
        for (size_t off = 0; off < s.size();) {
          const ssize_t n = ::write(STDOUT_FILENO, s.data() + off, s.size() - off);
          if (n < 0 && errno == EINTR) continue;
          if (n <= 0) return;
          off += static_cast<size_t>(n);
        }
      };
    }
  }

  int run() {
    for (const auto& p : planProcesses(project_, options_)) {  // may throw: nothing started yet
      children_.push_back(std::make_unique<Child>());
      children_.back()->plan = p;
    }
    int wake[2];
    if (pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0) throw LaunchError(std::string("pipe: ") + std::strerror(errno));
    wake_read_ = wake[0];
    SignalScope signals(wake[1], options_.handle_signals);
    int was_subreaper = 0;
    prctl(PR_GET_CHILD_SUBREAPER, &was_subreaper);
    prctl(PR_SET_CHILD_SUBREAPER, 1);
    for (const auto& c : children_) have_leader_ = have_leader_ || c->plan.exit_leader;
    for (auto& c : children_) {
      if (!c->plan.note.empty()) say(c->plan.label + ": " + c->plan.note);
      if (pendingStopSignal() != 0 || !spawn(*c)) break;
    }
    if (!stopping_ && pendingStopSignal() == 0) {
      say("started " + std::to_string(children_.size()) + " processes in " + project_.directory.string());
    }
    supervise();
    cleanup(wake[1]);
    prctl(PR_SET_CHILD_SUBREAPER, was_subreaper);
    return exit_code_;
  }

 private:
  void say(const std::string& line) { options_.output("tessera-up | " + line); }

  bool spawn(Child& c) {
    int out[2], err[2], status_pipe[2];
    if (pipe2(out, O_CLOEXEC) != 0 || pipe2(err, O_CLOEXEC) != 0 || pipe2(status_pipe, O_CLOEXEC) != 0) {
      return failStart(c, std::string("pipe: ") + std::strerror(errno));
    }
    // Everything the child needs is built before fork: after it only async-signal-safe calls.
    std::map<std::string, std::string> env;
    for (char** e = environ; e && *e; ++e) {
      const std::string kv(*e);
      const size_t eq = kv.find('=');
      if (eq != std::string::npos) env[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    for (const auto& [k, v] : c.plan.environment) env[k] = v;
    std::vector<std::string> env_strings;
    for (const auto& [k, v] : env) env_strings.push_back(k + "=" + v);
    std::vector<char*> envp, argv;
    for (auto& s : env_strings) envp.push_back(s.data());
    envp.push_back(nullptr);
    std::vector<std::string> args = c.plan.argv;
    for (auto& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    const std::string dir = project_.directory.string();
    const pid_t parent = getpid();

    const pid_t pid = fork();
    if (pid == 0) execChild(parent, dir.c_str(), c.plan.executable.c_str(), argv.data(), envp.data(), out[1], err[1], status_pipe[1]);
    close(out[1]);
    close(err[1]);
    close(status_pipe[1]);
    if (pid < 0) {
      close(out[0]);
      close(err[0]);
      close(status_pipe[0]);
      return failStart(c, std::string("fork: ") + std::strerror(errno));
    }
    setpgid(pid, pid);  // also here, so the group exists before we might signal it
    c.pid = pid;
    c.running = true;
    c.started = Clock::now();
    c.streams[0].fd = out[0];
    c.streams[1].fd = err[0];
    for (auto& s : c.streams) fcntl(s.fd, F_SETFL, O_NONBLOCK);
    int exec_errno = 0;
    ssize_t n;
    do {
      n = ::read(status_pipe[0], &exec_errno, sizeof exec_errno);  // EOF == exec succeeded
    } while (n < 0 && errno == EINTR);
    close(status_pipe[0]);
    if (n == static_cast<ssize_t>(sizeof exec_errno)) {
      int status = 0;
      waitpid(pid, &status, 0);  // it is exiting with 127 right now
      c.running = false;
      return failStart(c, c.plan.executable + ": " + std::strerror(exec_errno));
    }
    return true;
  }

  bool failStart(Child& c, const std::string& why) {
    stopFailed(c.plan.label + " could not be started (" + why + "); stopping the farm");
    return false;
  }

  // The farm cannot go on: says why, stops everything, and tessera-up exits 1.
  void stopFailed(const std::string& why) {
    say(why);
    exit_code_ = 1;
    beginStop();
  }

  void beginStop() {
    if (stopping_) return;
    stopping_ = true;
    for (auto& c : children_) {
      if (c->restart_at) say(c->plan.label + " will not be restarted: the farm is stopping");
      c->restart_at.reset();
    }
    deadline_ = Clock::now() + options_.stop_timeout;
    signalGroups(SIGTERM);
  }

  // Whole groups, reaped leaders included, so helpers a child started go too.
  void signalGroups(int signo) {
    for (auto& c : children_) {
      if (c->pid > 0) kill(-c->pid, signo);
    }
  }

  void emit(Child& c, Stream& s, bool flush_partial) {
    size_t start = 0;
    for (size_t nl; (nl = s.buf.find('\n', start)) != std::string::npos; start = nl + 1) {
      size_t end = nl;
      if (end > start && s.buf[end - 1] == '\r') --end;
      options_.output(c.plan.label + " | " + s.buf.substr(start, end - start));
    }
    s.buf.erase(0, start);
    if (!s.buf.empty() && (flush_partial || s.buf.size() >= kMaxLine)) {
      options_.output(c.plan.label + " | " + s.buf);
      s.buf.clear();
    }
  }

  // Reads what is available without blocking; closes the stream at EOF.
  void drain(Child& c, Stream& s) {
    char chunk[8192];
    while (s.fd >= 0) {
      const ssize_t n = ::read(s.fd, chunk, sizeof chunk);
      if (n > 0) {
        s.buf.append(chunk, static_cast<size_t>(n));
        emit(c, s, false);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n == 0) {
        emit(c, s, true);
        close(s.fd);
        s.fd = -1;
      }
      break;  // EAGAIN: nothing more for now
    }
  }

  void onExit(Child& c, int status) {
    c.running = false;
    for (auto& s : c.streams) drain(c, s);  // its last words come before the verdict
    if (stopping_) return;
    const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (clean && c.plan.exit_leader) {
      say(c.plan.label + " finished; stopping the farm");
      exit_code_ = 0;
      return beginStop();
    }
    const auto ran_for = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - c.started);
    const RestartVerdict v = judgeEnd(c.plan.restart, options_.restart, c.history, status, ran_for);
    const std::string ended = c.plan.label + (clean ? " exited (" : " died (") + describe(status) + ")";
    if (v.kind == RestartVerdict::Kind::Restart) {
      say(ended + "; restarting (restart: " + c.plan.restart.text() + ", attempt " + std::to_string(v.attempt) + ")");
      // Like a container, a restarted child starts with an empty group: no stray helpers.
      if (kill(-c.pid, 0) == 0) kill(-c.pid, SIGKILL);
      c.restart_at = Clock::now() + v.delay;
    } else if (clean) {
      // Stages finish on the master's Shutdown in any order; the farm is done when the
      // leader is (or, without a leader, when everything has finished).
      if (have_leader_) say(c.plan.label + " finished");
    } else if (v.kind == RestartVerdict::Kind::GiveUp) {
      // A replica that keeps dying while others of its service run (its host lost its route to
      // the master, say) is left out; with none left it stops the farm (a setup error, likely).
      if (const int others = otherLiveReplicas(c)) {
        if (kill(-c.pid, 0) == 0) kill(-c.pid, SIGKILL);  // no stray helpers of it stay behind
        say(ended + "; giving up on it: " + v.reason + "; the farm goes on with " + std::to_string(others) +
            " other " + c.plan.service + (others > 1 ? " replicas" : " replica"));
        return;
      }
      stopFailed(ended + "; giving up on it: " + v.reason + "; stopping the farm");
    } else if (WIFEXITED(status)) {
      // An error exit, not a crash: the process said why just above (a bad scene, say).
      stopFailed(c.plan.label + " stopped with an error (" + describe(status) +
                 "; its message is above): the farm cannot continue without it; stopping");
    } else {
      stopFailed(ended + ": the farm cannot continue without it; stopping");
    }
  }

  // Replicas of c's service other than c that run or wait out a restart's backoff.
  int otherLiveReplicas(const Child& c) const {
    int n = 0;
    for (const auto& o : children_) n += o.get() != &c && o->plan.service == c.plan.service && (o->running || o->restart_at);
    return n;
  }

  // Starts children whose backoff is over, with their original plan.
  void restartDue() {
    for (auto& c : children_) {
      if (stopping_ || !c->restart_at || Clock::now() < *c->restart_at) continue;
      c->restart_at.reset();
      for (auto& s : c->streams) {
        if (s.fd >= 0) {  // a helper of the old process may still hold its end open
          emit(*c, s, true);
          close(s.fd);
          s.fd = -1;
        }
      }
      if (spawn(*c)) say(c->plan.label + " restarted (pid " + std::to_string(c->pid) + ")");
    }
  }

  void supervise() {
    bool killed = false;
    Clock::time_point kill_deadline{};
    int seen_signal = 0;
    for (;;) {
      std::vector<pollfd> fds{{wake_read_, POLLIN, 0}};
      std::vector<std::pair<Child*, Stream*>> owners{{nullptr, nullptr}};
      for (auto& c : children_) {
        for (auto& s : c->streams) {
          if (s.fd >= 0) {
            fds.push_back({s.fd, POLLIN, 0});
            owners.emplace_back(c.get(), &s);
          }
        }
      }
      // The timeout bounds how late a deadline is noticed; SIGCHLD wakes us at once.
      if (poll(fds.data(), fds.size(), 100) > 0) {
        for (size_t i = 1; i < fds.size(); ++i) {
          if (fds[i].revents != 0) drain(*owners[i].first, *owners[i].second);
        }
        if (fds[0].revents != 0) {
          char junk[64];
          while (::read(wake_read_, junk, sizeof junk) > 0) {}
        }
      }
      reap();
      restartDue();
      if (pendingStopSignal() != 0 && pendingStopSignal() != seen_signal) {
        seen_signal = pendingStopSignal();
        if (!stopping_) {
          say(std::string("received SIG") + sigabbrev_np(seen_signal) + "; stopping the farm");
          exit_code_ = 128 + seen_signal;
          beginStop();
        } else if (!killed) {
          deadline_ = Clock::now();  // a second Ctrl-C: no more patience
        }
        clearStopSignal();
        seen_signal = 0;
      }
      bool any_running = false;
      for (auto& c : children_) any_running = any_running || c->running || c->restart_at;
      if (!any_running) {
        if (!groupsAlive()) return;
        beginStop();  // helpers a finished child left behind in its group
      }
      if (stopping_ && !killed && Clock::now() >= deadline_) {
        for (auto& c : children_) {
          if (c->running) say(c->plan.label + " did not stop in time; sending SIGKILL");
          else if (c->pid > 0 && kill(-c->pid, 0) == 0) say(c->plan.label + "'s helper processes did not stop in time; sending SIGKILL");
        }
        signalGroups(SIGKILL);
        killed = true;
        kill_deadline = Clock::now() + kKillWait;
      }
      if (killed && Clock::now() >= kill_deadline) {
        bool stuck = false;
        for (auto& c : children_) {
          if (c->running) say(c->plan.label + " (pid " + std::to_string(c->pid) + ") could not be reaped");
          stuck = stuck || c->running;
        }
        if (stuck && exit_code_ == 0) exit_code_ = 1;
        return;
      }
    }
  }

  // As a child subreaper the launcher inherits its children's orphans; reaping them
  // (waitpid(-1)) is what lets their process groups disappear.
  void reap() {
    int status = 0;
    for (pid_t pid; (pid = waitpid(-1, &status, WNOHANG)) > 0;) {
      for (auto& c : children_) {
        if (c->running && c->pid == pid) onExit(*c, status);
      }
    }
  }

  bool groupsAlive() const {
    for (const auto& c : children_) {
      if (c->pid > 0 && kill(-c->pid, 0) == 0) return true;
    }
    return false;
  }

  void cleanup(int wake_write) {
    // Leftover members of the children's groups (background helpers) must not outlive us.
    for (auto& c : children_) {
      if (c->pid > 0 && kill(-c->pid, 0) == 0) kill(-c->pid, SIGKILL);
      for (auto& s : c->streams) {
        drain(*c, s);
        if (s.fd >= 0) {
          emit(*c, s, true);
          close(s.fd);
          s.fd = -1;
        }
      }
    }
    close(wake_read_);
    close(wake_write);
  }

  const ComposeProject& project_;
  LaunchOptions options_;
  std::vector<std::unique_ptr<Child>> children_;
  int wake_read_ = -1;
  bool have_leader_ = false;
  bool stopping_ = false;
  Clock::time_point deadline_{};
  int exit_code_ = 0;
};

}  // namespace

int launch(const ComposeProject& project, const LaunchOptions& options) {
  if (SignalScope::active()) throw LaunchError("launch() is already running in this process");
  Supervisor supervisor(project, options);
  return supervisor.run();
}

}  // namespace tessera::launcher
