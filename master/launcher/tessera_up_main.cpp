// tessera-up: runs compose.yaml as local processes, no container engine needed.
//   tessera-up [FILE] [--env KEY=VALUE]... [--dry-run] [--launch-with CMD] [--slurm]
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>

#include "common/net/log.h"
#include "master/launcher/compose.h"
#include "master/launcher/launcher.h"
#include "master/launcher/output_lock.h"
#include "master/launcher/settings.h"
#include "master/launcher/slurm.h"

extern char** environ;

namespace {

// Returns false if some executable was not found.
bool printPlan(const tessera::launcher::ComposeProject& project,
               const std::vector<tessera::launcher::PlannedProcess>& plan) {
  std::cout << "project " << project.name << " (runs in " << project.directory.string() << ")\n";
  if (!plan.empty()) std::cout << "PATH=" << plan.front().environment.at("PATH") << "\n";
  bool all_found = true;
  for (const auto& p : plan) {
    std::cout << p.label << (p.exit_leader ? " [exit leader]" : "");
    if (p.restart.mode != tessera::launcher::RestartPolicy::Mode::No) std::cout << " [restart: " << p.restart.text() << "]";
    std::cout << "\n";
    std::cout << "  argv: " << tessera::launcher::quoteCommand(p.argv) << "\n";
    std::cout << "  executable: " << (p.executable.empty() ? "NOT FOUND on PATH" : p.executable) << "\n";
    if (!p.note.empty()) std::cout << "  note: " << p.note << "\n";
    for (const auto& [k, v] : p.environment) {
      if (k != "PATH") std::cout << "  env: " << k << "=" << tessera::launcher::quoteCommand({v}) << "\n";
    }
    all_found = all_found && !p.executable.empty();
  }
  return all_found;
}

// Checks the user's TESSERA_* settings (--env, environment, the .env beside the file) and
// puts absolute paths in their place; logs what it found. Returns the output folder.
std::filesystem::path checkUserSettings(const std::string& file, tessera::launcher::ComposeOptions& options,
                       const std::shared_ptr<spdlog::logger>& log) {
  namespace launcher = tessera::launcher;
  std::map<std::string, std::string> dotenv;
  const auto dotenv_path = std::filesystem::absolute(file).parent_path() / ".env";
  if (std::ifstream in{dotenv_path}) {
    std::stringstream text;
    text << in.rdbuf();
    dotenv = launcher::parseDotEnv(text.str(), dotenv_path.string());
  }
  std::vector<std::string> names;
  for (const auto& [k, v] : options.overrides) names.push_back(k);
  for (const auto& [k, v] : dotenv) names.push_back(k);
  for (char** e = environ; *e; ++e) names.emplace_back(*e, std::strchr(*e, '=') ? std::strchr(*e, '=') - *e : 0);
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  auto lookup = [&](const std::string& k) -> std::optional<std::string> {
    if (auto it = options.overrides.find(k); it != options.overrides.end()) return it->second;
    if (const char* v = std::getenv(k.c_str())) return std::string(v);
    if (auto it = dotenv.find(k); it != dotenv.end()) return it->second;
    return std::nullopt;
  };
  const auto checked = launcher::checkSettings(names, lookup, std::filesystem::current_path());
  for (const auto& w : checked.warnings) log->warn("{}", w);
  for (const auto& [k, v] : checked.overrides) options.overrides[k] = v;
  const auto out = lookup("TESSERA_OUT");
  const std::filesystem::path folder =
      out && !out->empty() ? std::filesystem::path(*out) : std::filesystem::absolute(file).parent_path() / "out";
  log->info("frames and metrics go to {}", folder.string());
  return folder;
}

// 48 random bits as 12 hex digits: the run's identity (TESSERA_RUN).
std::string newRunId() {
  std::random_device rd;
  const uint64_t bits = ((uint64_t)rd() << 16) ^ rd();
  char id[16];
  std::snprintf(id, sizeof id, "%012llx", (unsigned long long)(bits & 0xffffffffffffULL));
  return id;
}

// The ipc folder the farm's endpoints live in when it is this run's own (named after the
// run, as compose.yaml's default makes it); "" otherwise (the user's own endpoints).
std::filesystem::path runFolder(const tessera::launcher::ComposeProject& project, const std::string& run) {
  for (const auto& service : project.services) {
    auto it = service.environment.find("TESSERA_ENDPOINTS");
    if (it == service.environment.end() || it->second.rfind("ipc://", 0) != 0) continue;
    const std::filesystem::path folder = it->second.substr(6);
    if (folder.filename() == run) return folder;
  }
  return {};
}

// tessera-up --slurm: one farm per output folder, as locally.
int slurmFarm(const std::string& file, const tessera::launcher::ComposeOptions& options,
              const std::filesystem::path& out_folder, bool dry_run) {
  std::optional<tessera::launcher::OutputLock> out_lock;
  if (!dry_run) {
    out_lock.emplace(out_folder);
    tessera::launcher::removeOldFrames(out_folder);
  }
  return tessera::launcher::runSlurm(file, options, dry_run);
}

// tessera-up --slurm-task: errors before the stage starts name the task and the node.
int slurmTask(const std::string& file, const std::string& run_dir, const std::string& service, int replica,
              const std::shared_ptr<spdlog::logger>& log) {
  try {
    return tessera::launcher::runSlurmTask(file, run_dir, service, replica);
  } catch (const std::exception& e) {
    const char* task = std::getenv("SLURM_PROCID");
    const char* node = std::getenv("SLURMD_NODENAME");
    log->error("{} (task {} on {}): {}", service, task ? task : "?", node ? node : "?", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  auto log = tessera::setupLogging("tessera-up");
  CLI::App app{"Runs a compose.yaml farm as local processes (no container engine)."};
  app.option_defaults()->always_capture_default();  // --help shows every default
  std::string file = "compose.yaml";
  std::vector<std::string> env_args;
  bool dry_run = false;
  std::string launch_with;
  app.add_option("file", file, "Compose file")->capture_default_str();
  app.add_option("--env", env_args, "Variable for interpolation, KEY=VALUE (wins over the "
                                    "environment and .env)");
  app.add_flag("--dry-run", dry_run, "Print the resolved processes, argv and environment; start nothing");
  app.add_option("--launch-with", launch_with,
                 "Start every process through this command (e.g. \"srun -N1 -n1\"); it gets the "
                 "stage's command line and TESSERA_SERVICE/TESSERA_REPLICA in its environment");
  bool slurm = false;
  app.add_flag("--slurm", slurm, "Run the farm as one Slurm job step (srun --multi-prog) inside this "
                                 "allocation; with --dry-run print the step's configuration");
  std::string task_service, run_dir;
  int offset = 0;
  auto* task = app.add_option("--slurm-task", task_service, "(used by --slurm) run this service's task")->group("");
  app.add_option("--offset", offset, "(with --slurm-task) replica - 1")->group("");
  app.add_option("--run-dir", run_dir, "(with --slurm-task) the step's run folder")->group("");
  CLI11_PARSE(app, argc, argv);
  if (*task) return slurmTask(file, run_dir, task_service, offset + 1, log);

  try {
    tessera::launcher::ComposeOptions options;
    for (const std::string& kv : env_args) {
      const size_t eq = kv.find('=');
      if (eq == 0 || eq == std::string::npos) throw std::runtime_error("--env " + kv + ": expected KEY=VALUE");
      options.overrides[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    const std::filesystem::path out_folder = checkUserSettings(file, options, log);
    if (slurm) return slurmFarm(file, options, out_folder, dry_run);
    // One identity per run: stages say it in their Hello and a master refuses another run's;
    // compose.yaml's default endpoints are a folder named after it, so two farms never meet.
    if (!options.overrides.count("TESSERA_RUN") && !std::getenv("TESSERA_RUN"))
      options.overrides["TESSERA_RUN"] = newRunId();
    const std::string run = options.overrides.count("TESSERA_RUN") ? options.overrides["TESSERA_RUN"]
                                                                    : std::getenv("TESSERA_RUN");
    const auto project = tessera::launcher::loadCompose(file, options);
    for (const auto& w : project.warnings) log->warn("{}", w);
    const std::filesystem::path folder = runFolder(project, run);
    tessera::launcher::LaunchOptions launch_options;
    if (!launch_with.empty()) {
      launch_options.launch_with = tessera::launcher::splitCommandLine(launch_with, "--launch-with");
    }
    if (dry_run) {
      return printPlan(project, tessera::launcher::planProcesses(project, launch_options, true)) ? 0 : 1;
    }
    const tessera::launcher::OutputLock out_lock(out_folder);  // one farm per output folder
    if (const int old = tessera::launcher::removeOldFrames(out_folder); old > 0)
      log->info("removed {} frame files of an earlier run from {}", old, out_folder.string());
    if (!folder.empty()) log->info("run {}: sockets in {}", run, folder.string());
    // Removed at the end only if this launch made it: a folder already there may be a live
    // farm's of the same TESSERA_RUN (refused at its endpoints), whose sockets must stay.
    std::error_code ignored;
    const bool own_folder = !folder.empty() && std::filesystem::create_directories(folder, ignored);
    const int rc = tessera::launcher::launch(project, launch_options);
    if (own_folder) std::filesystem::remove_all(folder, ignored);
    else if (!folder.empty()) std::filesystem::remove(folder, ignored);  // only if empty: a killed run's, not a live farm's
    return rc;
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 2;
  }
}
