// Turns a ComposeProject into the list of processes to start: executables resolved
// against a PATH that puts the build's own binaries first. See launcher.h.
#include <unistd.h>

#include <cstdlib>
#include <system_error>

#include "master/launcher/launcher.h"

namespace tessera::launcher {
namespace {

bool isExecutableFile(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

std::string searchPath(const std::string& name, const std::string& path, const std::filesystem::path& cwd) {
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find(':', start);
    if (end == std::string::npos) end = path.size();
    std::filesystem::path dir = path.substr(start, end - start);
    if (dir.empty()) dir = cwd;  // an empty PATH entry means the current folder
    if (isExecutableFile(dir / name)) return (dir / name).string();
    start = end + 1;
  }
  return {};
}

}  // namespace

std::vector<std::filesystem::path> defaultBinaryDirectories() {
  // The build puts every executable in build/bin and the image in /usr/local/bin, so the
  // launcher's own folder holds the whole farm.
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  return {exe.parent_path()};
}

std::string resolveExecutable(const std::string& cmd, const std::string& path, const std::filesystem::path& cwd) {
  if (cmd.empty()) return {};
  if (cmd.find('/') == std::string::npos) return searchPath(cmd, path, cwd);
  const std::filesystem::path p = std::filesystem::path(cmd).is_absolute() ? std::filesystem::path(cmd) : cwd / cmd;
  if (isExecutableFile(p)) return p.lexically_normal().string();
  if (std::filesystem::path(cmd).is_absolute()) {
    return searchPath(std::filesystem::path(cmd).filename().string(), path, cwd);
  }
  return {};
}

std::vector<PlannedProcess> planProcesses(const ComposeProject& project, const LaunchOptions& options,
                                          bool allow_missing) {
  std::vector<std::filesystem::path> dirs = options.binary_dirs;
  if (options.use_default_binary_dirs) {
    for (auto& d : defaultBinaryDirectories()) dirs.push_back(d);
  }
  std::string prefix;
  for (const auto& d : dirs) prefix += d.string() + ":";
  const char* inherited = std::getenv("PATH");
  std::vector<PlannedProcess> plan;
  for (const ComposeService& s : project.services) {
    auto own_path = s.environment.find("PATH");
    const std::string path = prefix + (own_path != s.environment.end()
                                           ? own_path->second
                                           : std::string(inherited ? inherited : "/usr/local/bin:/usr/bin:/bin"));
    const std::string exe = resolveExecutable(s.argv.front(), path, project.directory);
    if (exe.empty() && !allow_missing) {
      throw LaunchError("services." + s.name + ": command \"" + s.argv.front() +
                        "\" not found (PATH=" + path + ")");
    }
    std::string wrapper;
    if (!options.launch_with.empty()) {
      wrapper = resolveExecutable(options.launch_with.front(), path, project.directory);
      if (wrapper.empty() && !allow_missing) {
        throw LaunchError("--launch-with: command \"" + options.launch_with.front() + "\" not found (PATH=" + path + ")");
      }
    }
    for (int r = 1; r <= s.replicas; ++r) {
      if (options.only && (options.only->service != s.name || options.only->replica != r)) continue;
      PlannedProcess p;
      p.service = s.name;
      p.replica = r;
      p.label = s.replicas > 1 ? s.name + "-" + std::to_string(r) : s.name;
      if (options.only) p.label = options.only->label;
      p.exit_leader = s.exit_leader;
      p.restart = s.restart;
      p.executable = exe;
      p.argv = s.argv;
      p.environment = s.environment;
      p.environment["PATH"] = path;
      p.environment["TESSERA_SERVICE"] = s.name;
      p.environment["TESSERA_REPLICA"] = std::to_string(r);
      if (!exe.empty() && exe != s.argv.front() && s.argv.front().find('/') != std::string::npos &&
          std::filesystem::path(s.argv.front()).is_absolute()) {
        p.note = s.argv.front() + " does not exist here; using " + exe;
      }
      if (!options.launch_with.empty()) {
        std::vector<std::string> argv = options.launch_with;
        argv.push_back(exe.empty() ? s.argv.front() : exe);
        argv.insert(argv.end(), s.argv.begin() + 1, s.argv.end());
        p.note = "started through " + options.launch_with.front();
        p.argv = std::move(argv);
        p.executable = wrapper;
      }
      plan.push_back(std::move(p));
    }
  }
  return plan;
}

}  // namespace tessera::launcher
