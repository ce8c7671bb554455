// tessera-up --slurm: the compose project as one srun --multi-prog job step. See slurm.h.
#include "master/launcher/slurm.h"

#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

#include "common/net/curve.h"
#include "common/net/endpoints.h"
#include "master/launcher/launcher.h"

extern char** environ;

namespace tessera::launcher {
namespace {

// The first farm number whose run folder does not exist yet (mkdir is the claim).
int claimFarmNumber(const std::filesystem::path& base, const std::string& job, bool dry_run) {
  if (!dry_run) std::filesystem::create_directories(base);
  for (int farm = 1; farm < 1000; ++farm) {
    const auto dir = base / (job + "-" + std::to_string(farm));
    if (dry_run) {
      if (!std::filesystem::exists(dir)) return farm;
    } else if (::mkdir(dir.c_str(), 0700) == 0) {
      return farm;
    } else if (errno != EEXIST) {
      throw LaunchError("cannot create the run folder " + dir.string() + ": " + std::strerror(errno));
    }
  }
  throw LaunchError("999 run folders of job " + job + " in " + base.string() + ": remove old ones");
}

// While the sruns run, SIGINT/SIGTERM to tessera-up become SIGTERM to them (srun then ends
// its step at once; one SIGINT would only make it print its tasks); the run folder is
// removed after them. Plain arrays: the handler may run at any point of the spawning.
constexpr int kMaxSruns = 2;
pid_t g_sruns[kMaxSruns];
volatile sig_atomic_t g_nsruns = 0, g_stop = 0;
void forward(int) {
  g_stop = 1;
  for (int i = 0; i < g_nsruns; ++i) kill(g_sruns[i], SIGTERM);
}

// Runs the steps side by side; when one ends in failure the others are stopped (a farm
// without its display or master cannot go on). Returns the first failure's code, or 0.
int runSruns(const std::vector<std::vector<std::string>>& cmds) {
  struct sigaction sa {}, old_int{}, old_term{};
  sa.sa_handler = forward;
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);
  std::string failed;
  for (const auto& cmd : cmds) {
    std::vector<char*> argv;
    for (const auto& s : cmd) argv.push_back(const_cast<char*>(s.c_str()));
    argv.push_back(nullptr);
    pid_t pid = -1;
    if (g_stop || g_nsruns >= kMaxSruns) break;
    if (const int rc = posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ); rc != 0) {
      failed = "cannot start srun: " + std::string(std::strerror(rc)) + " (is slurm-client installed?)";
      break;
    }
    g_sruns[g_nsruns] = pid;
    g_nsruns = g_nsruns + 1;
  }
  if (g_stop || !failed.empty()) forward(SIGTERM);
  int rc = failed.empty() ? 0 : 1;
  for (int left = g_nsruns; left > 0;) {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0 && errno == EINTR) continue;
    if (pid < 0) break;
    --left;
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (code != 0 && rc == 0) {
      rc = code;
      forward(SIGTERM);
    }
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  g_nsruns = 0;
  g_stop = 0;
  if (!failed.empty()) throw LaunchError(failed);
  return rc;
}

std::string ranksText(const SlurmTaskRange& r) {
  std::string text = std::to_string(r.first);
  if (r.last > r.first) text.append("-").append(std::to_string(r.last));
  return text;
}

// What each task learns at start from the rendezvous files, as placeholders.
ComposeOptions withPlaceholders(ComposeOptions options) {
  options.overrides["TESSERA_ENDPOINTS"] = "tcp://MASTER_ADDRESS:PORT";
  options.overrides["TESSERA_DISPLAY_HOST"] = "DISPLAY_ADDRESS";
  options.overrides["TESSERA_BIND_HOST"] = "NODE_ADDRESS";
  options.overrides["TESSERA_ADVERTISE_HOST"] = "NODE_ADDRESS";
  return options;
}

void printDryRun(const SlurmPlan& plan, const std::filesystem::path& compose_file, const ComposeOptions& options,
                 const std::vector<std::string>& confs) {
  const ComposeProject project = loadCompose(compose_file, withPlaceholders(options));
  int tasks = 0;
  for (const auto& step : plan.steps) tasks += step.tasks;
  std::cout << "# tessera-up --slurm: project " << project.name << ", job " << plan.job << ", farm " << plan.farm
            << ", " << tasks << " tasks\n# run folder " << plan.run_dir.string() << " (mode 0700, removed when the step ends)\n";
  for (size_t i = 0; i < plan.steps.size(); ++i) {
    std::cout << quoteCommand(srunCommand(plan, plan.steps[i])) << "\n--- " << plan.steps[i].conf << "\n" << confs[i];
  }
  std::cout << "--- settings.env\n" << settingsText(plan.settings) << "--- services\n";
  for (const auto& step : plan.steps) {
    for (const auto& r : step.ranges) {
      const ComposeService& s = *project.find(r.service);
      std::cout << s.name << ": tasks " << ranksText(r) << (s.exit_leader ? " [exit leader]" : "")
                << (s.restart.mode != RestartPolicy::Mode::No ? " [restart: " + s.restart.text() + "]" : "") << "\n";
      std::cout << "  argv: " << quoteCommand(s.argv) << "\n";
      for (const auto& [k, v] : s.environment) std::cout << "  env: " << k << "=" << quoteCommand({v}) << "\n";
    }
  }
}

}  // namespace

std::vector<SlurmStep> slurmSteps(const ComposeProject& project, int het_size) {
  if (het_size > 2) {
    throw LaunchError("a heterogeneous job for tessera-up --slurm has 2 components (the display's node, then the "
                      "farm's nodes); this one has " + std::to_string(het_size));
  }
  for (const char* needed : {"master", "display"}) {
    const ComposeService* s = project.find(needed);
    if (!s || s->replicas != 1)
      throw LaunchError(std::string("tessera-up --slurm needs exactly one '") + needed + "' service (" +
                        (s ? std::to_string(s->replicas) + " replicas" : "none") + " in the compose file)");
  }
  // Compositors use base+10+rank of the master's 100-port block (rank 89 at most).
  if (const ComposeService* c = project.find("compositor"); c && c->replicas > 89)
    throw LaunchError("tessera-up --slurm runs at most 89 compositors, not " + std::to_string(c->replicas));
  std::vector<SlurmStep> steps(het_size == 2 ? 2 : 1);
  for (const auto& s : project.services) {
    if (s.replicas == 0) continue;  // e.g. no compositor for a binary-swap farm
    SlurmStep& step = het_size == 2 && s.name != "display" ? steps[1] : steps[0];
    step.ranges.push_back({step.tasks, step.tasks + s.replicas - 1, s.name});
    step.tasks += s.replicas;
  }
  if (het_size == 2) {
    if (steps[0].tasks == 0) throw LaunchError("a heterogeneous job runs the display in component 0: no display service");
    for (int g = 0; g < 2; ++g) {
      steps[g].het_group = g;
      steps[g].conf = "multi-prog-" + std::to_string(g) + ".conf";
    }
  } else {
    steps[0].conf = "multi-prog.conf";
  }
  return steps;
}

int slurmFirstPort(const std::string& job, int farm) {
  unsigned long id = 0;
  for (char c : job) id = id * 10 + (std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : 0);
  // 220 blocks of 100 in 10000..31999, below Linux's ephemeral ports (32768..): the farms of
  // one job, and jobs with neighbouring ids, start blocks apart.
  return 10000 + static_cast<int>((id * 7 + static_cast<unsigned long>(farm) * 53) % 220) * 100;
}

std::string multiProgConfig(const SlurmPlan& plan, const SlurmStep& step, const std::string& tessera_up,
                            const std::string& compose_file) {
  std::string out = "# Tessera farm " + plan.settings.at("TESSERA_RUN") + ": task ranks -> services (%o: replica - 1)\n";
  for (const auto& r : step.ranges) {
    out += ranksText(r) + " " + quoteCommand({tessera_up, "--slurm-task", r.service, "--offset"}) + " %o " +
           quoteCommand({"--run-dir", plan.run_dir.string(), compose_file}) + "\n";
  }
  return out;
}

std::vector<std::string> srunCommand(const SlurmPlan& plan, const SlurmStep& step) {
  // A lost task is not the farm's end (--kill-on-bad-exit=0, --wait=0: whatever the site's
  // defaults): a lost renderer or compositor is worked around; the master's or display's
  // task cancels the step itself when its process is lost.
  std::vector<std::string> cmd{"srun"};
  if (step.het_group >= 0) cmd.push_back("--het-group=" + std::to_string(step.het_group));
  cmd.push_back("--ntasks=" + std::to_string(step.tasks));
  cmd.push_back("--kill-on-bad-exit=0");
  cmd.push_back("--wait=0");
  cmd.push_back("--multi-prog");
  cmd.push_back((plan.run_dir / step.conf).string());
  return cmd;
}

std::string settingsText(const std::map<std::string, std::string>& settings) {
  std::string out;
  for (const auto& [k, v] : settings) {  // as parseDotEnv reads double quotes
    out += k + "=\"";
    for (char c : v) {
      if (c == '\n') out += "\\n";
      else if (c == '\t') out += "\\t";
      else if (c == '"' || c == '\\') out += std::string("\\") + c;
      else out += c;
    }
    out += "\"\n";
  }
  return out;
}

namespace {

// SLURM_NTASKS of the step's allocation (or its heterogeneous component); 0 if unknown.
int allocatedTasks(const SlurmStep& step) {
  const std::string name = step.het_group < 0 ? "SLURM_NTASKS" : "SLURM_NTASKS_HET_GROUP_" + std::to_string(step.het_group);
  return std::atoi(envOr(name.c_str(), "0").c_str());
}

void writeFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw LaunchError("cannot write " + path.string() + ": " + std::strerror(errno));
}

void checkAllocation(const SlurmPlan& plan) {
  if (!envOr("SLURM_OVERCOMMIT", "").empty()) return;  // tasks share CPUs by request
  for (const auto& step : plan.steps) {
    const int allocated = allocatedTasks(step);
    if (allocated == 0 || allocated >= step.tasks) continue;
    const std::string where = step.het_group < 0 ? "this allocation" : "component " + std::to_string(step.het_group);
    throw LaunchError("the farm needs " + std::to_string(step.tasks) + " tasks in " + where +
                      " (one per process: tessera-up --slurm --dry-run lists them) but it has " +
                      std::to_string(allocated) + ": sbatch --ntasks=" + std::to_string(step.tasks) +
                      " (or --overcommit to share CPUs)");
  }
}

}  // namespace

int runSlurm(const std::filesystem::path& compose_file, const ComposeOptions& user_options, bool dry_run) {
  const char* job = std::getenv("SLURM_JOB_ID");
  if ((!job || !*job) && !dry_run) {
    throw LaunchError("tessera-up --slurm runs inside a Slurm allocation (an sbatch script or salloc): "
                      "SLURM_JOB_ID is not set");
  }
  const std::filesystem::path file = std::filesystem::absolute(compose_file);
  ComposeOptions options = user_options;
  SlurmPlan plan;
  plan.job = job && *job ? job : "JOB";  // a dry run outside an allocation
  plan.steps = slurmSteps(loadCompose(file, withPlaceholders(options)), std::atoi(envOr("SLURM_HET_SIZE", "0").c_str()));
  if (!dry_run) checkAllocation(plan);
  const auto base = std::filesystem::current_path() / ".tessera-slurm";
  plan.farm = claimFarmNumber(base, plan.job, dry_run);
  plan.run_dir = base / (plan.job + "-" + std::to_string(plan.farm));
  auto removeRunFolder = [&] {
    std::error_code ignored;
    std::filesystem::remove_all(plan.run_dir, ignored);  // the keys go with it
    std::filesystem::remove(base, ignored);              // when no other farm is in it
  };
  try {
    // The farm's identity and keys are the run's own: two farms never mix, even on one node.
    options.overrides["TESSERA_RUN"] = "slurm-" + plan.job + "-" + std::to_string(plan.farm);
    options.overrides["TESSERA_CURVE"] = "on";
    options.overrides["TESSERA_KEYS"] = (plan.run_dir / "keys").string();
    plan.settings = options.overrides;
    const auto self = defaultBinaryDirectories();
    const std::string tessera_up = self.empty() ? "tessera-up" : (self.front() / "tessera-up").string();
    std::vector<std::string> confs;
    for (const auto& step : plan.steps) confs.push_back(multiProgConfig(plan, step, tessera_up, file.string()));
    if (dry_run) {
      printDryRun(plan, file, options, confs);
      return 0;
    }
    writeFarmKeys((plan.run_dir / "keys").string(), generateFarmKeys());
    writeFile(plan.run_dir / "settings.env", settingsText(plan.settings));
    std::vector<std::vector<std::string>> cmds;
    std::string table;
    for (size_t i = 0; i < plan.steps.size(); ++i) {
      writeFile(plan.run_dir / plan.steps[i].conf, confs[i]);
      cmds.push_back(srunCommand(plan, plan.steps[i]));
      for (const auto& r : plan.steps[i].ranges) table += " " + r.service + "=" + ranksText(r);
      if (plan.steps.size() > 1) table += i + 1 < plan.steps.size() ? " |" : "";
    }
    std::cout << "tessera-up | farm " << plan.settings["TESSERA_RUN"] << ", run folder " << plan.run_dir.string()
              << ", tasks:" << table << std::endl;
    int rc = runSruns(cmds);
    if (rc != 0 && std::filesystem::exists(plan.run_dir / "finished")) {
      std::cout << "tessera-up | the display finished the farm's frames; srun's exit code " << rc
                << " counts tasks lost on the way" << std::endl;
      rc = 0;
    }
    removeRunFolder();
    if (rc != 0) std::cout << "tessera-up | the farm's job step ended with exit code " << rc << std::endl;
    return rc;
  } catch (...) {
    if (!dry_run) removeRunFolder();
    throw;
  }
}

}  // namespace tessera::launcher
