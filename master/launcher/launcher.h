// Runs a ComposeProject as local child processes (tessera-up): one process per replica,
// output lines prefixed "<service>[-<replica>] | ", a clean bounded stop of the whole farm.
// launch() is not reentrant: it owns SIGINT/SIGTERM/SIGCHLD/SIGPIPE while it runs.
#pragma once
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "master/launcher/compose.h"
#include "master/launcher/restart.h"

namespace tessera::launcher {

class LaunchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LaunchOptions {
  // Receives every complete output line (without '\n'), already prefixed; launcher's own
  // lines are prefixed "tessera-up | ". Default: written to stdout, one write per line.
  std::function<void(std::string_view line)> output;
  // SIGTERM -> SIGKILL grace period when stopping the farm.
  std::chrono::milliseconds stop_timeout{5000};
  // Folders put first on the children's PATH; default: defaultBinaryDirectories().
  std::vector<std::filesystem::path> binary_dirs;
  bool use_default_binary_dirs = true;
  // Stop the farm on SIGINT/SIGTERM to this process (exit 128 + signal).
  bool handle_signals = true;
  // Backoff and crash-loop bound for services with a `restart:` policy.
  RestartLimits restart;
  // A command that starts each process in its place (`srun -N1 -n1`, `ssh host`, or the
  // emulated cluster's per-host wrapper): argv becomes launch_with + [executable, args...].
  // The wrapper sees TESSERA_SERVICE/TESSERA_REPLICA, so it can pick the host per process.
  std::vector<std::string> launch_with;
  // Start only this replica of this service, under this label (a Slurm task runs one).
  struct Only {
    std::string service;
    int replica = 1;
    std::string label;
  };
  std::optional<Only> only;
};

// One child process to start.
struct PlannedProcess {
  std::string label;    // "master", or "renderer-2" when the service has several replicas
  std::string service;
  int replica = 1;      // 1-based, as TESSERA_REPLICA
  bool exit_leader = false;
  RestartPolicy restart;
  std::string executable;  // resolved path of argv[0]
  std::vector<std::string> argv;
  // Added on top of the launcher's own environment: the service's variables, PATH with
  // the binary folders first, TESSERA_SERVICE and TESSERA_REPLICA.
  std::map<std::string, std::string> environment;
  std::string note;  // why the executable differs from argv[0], if it does
};

// The launcher's own folder (from /proc/self/exe): build/bin, or /usr/local/bin in the image.
std::vector<std::filesystem::path> defaultBinaryDirectories();

// Resolves argv[0] of `cmd` against `path` (a PATH value). A relative name with a '/' is
// taken from `cwd`; an absolute path that does not exist here (an image path such as
// /usr/local/bin/tessera-master) falls back to its file name on PATH. Empty if not found.
std::string resolveExecutable(const std::string& cmd, const std::string& path,
                              const std::filesystem::path& cwd);

// Every process in start order. Throws LaunchError naming the service whose command is
// not found, unless `allow_missing` (dry runs): then `executable` is empty.
std::vector<PlannedProcess> planProcesses(const ComposeProject& project, const LaunchOptions& options,
                                          bool allow_missing = false);

// Starts the farm and supervises it until it ends; returns the exit code:
// 0 when an exit leader exits 0 (others exiting 0 before it is normal: stages end on
// the master's Shutdown in any order), or, with no leader, when every process exited 0;
// 128+signal when stopped by SIGINT/SIGTERM; 1 when a process died that its service's
// `restart:` policy does not restart (or that gave up: retry limit, crash loop) or a
// process could not be started. A child its policy restarts is started again with the
// same plan after a backoff, never once the farm is stopping. Every child is stopped and
// reaped before returning.
int launch(const ComposeProject& project, const LaunchOptions& options);

}  // namespace tessera::launcher
