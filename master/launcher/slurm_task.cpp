// tessera-up --slurm-task: one task of the farm's job step. It learns where the master and
// the display are from the run folder (the master's and display's tasks write them), then
// runs its stage through launch() as tessera-up would, restart policy included. See slurm.h.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "common/net/endpoints.h"
#include "master/launcher/launcher.h"
#include "master/launcher/slurm.h"

namespace tessera::launcher {
namespace {

constexpr auto kRendezvousWait = std::chrono::seconds(60);  // all tasks start together

// The node's address as the cluster knows it (NodeAddr), so that other nodes reach it; the
// host name when scontrol cannot say.
std::string nodeAddress(const std::string& node) {
  const std::string cmd = "scontrol show node -o '" + node + "' 2>/dev/null";
  std::string text;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
    pclose(p);
  }
  const size_t at = text.find("NodeAddr=");
  if (at != std::string::npos) {
    const size_t end = text.find_first_of(" \n", at);
    const std::string addr = text.substr(at + 9, end - at - 9);
    if (!addr.empty()) return addr;
  }
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  return host;
}

// Whether a TCP port can be bound on `addr` now (an IPv4 literal; otherwise any address).
bool portFree(const std::string& addr, int port) {
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(static_cast<uint16_t>(port));
  if (inet_pton(AF_INET, addr.c_str(), &sa.sin_addr) != 1) sa.sin_addr.s_addr = htonl(INADDR_ANY);
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return true;
  const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) == 0;
  close(fd);
  return ok;
}

// The master's base port: the first candidate whose ports (base..base+2, base+10+rank) are
// free on this node now (the display's and compositors' nodes are not asked: a port taken
// there is an error that names it).
int chooseBasePort(const std::string& addr, int first, int compositors) {
  for (int k = 0; k < 20; ++k) {
    const int base = 10000 + (first - 10000 + 100 * k) % 22000;
    bool free = portFree(addr, base) && portFree(addr, base + 1) && portFree(addr, base + 2);
    for (int r = 0; free && r < compositors; ++r) free = portFree(addr, base + 10 + r);
    if (free) return base;
  }
  throw LaunchError("no free port range for the master on " + addr + " (tried 20 from " + std::to_string(first) + ")");
}

// Written whole or not at all: readers never see half an address.
void publish(const std::filesystem::path& file, const std::string& value) {
  const auto tmp = file.string() + ".tmp";
  std::ofstream(tmp) << value << "\n";
  std::filesystem::rename(tmp, file);
}

std::string awaitFile(const std::filesystem::path& file, const std::string& who) {
  const auto deadline = std::chrono::steady_clock::now() + kRendezvousWait;
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(file);
    std::string value;
    if (in >> value && !value.empty()) return value;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  throw LaunchError("no " + file.string() + " after " + std::to_string(kRendezvousWait.count()) + " s: the " + who +
                    "'s task did not start (see its output)");
}

std::map<std::string, std::string> readSettings(const std::filesystem::path& run_dir) {
  std::ifstream in(run_dir / "settings.env");
  if (!in) throw LaunchError("cannot read " + (run_dir / "settings.env").string() + ": is the run folder shared?");
  std::stringstream text;
  text << in.rdbuf();
  return parseDotEnv(text.str(), (run_dir / "settings.env").string());
}

}  // namespace

int runSlurmTask(const std::filesystem::path& compose_file, const std::filesystem::path& run_dir,
                 const std::string& service, int replica) {
  const std::string node = envOr("SLURMD_NODENAME", "?");
  const std::string task = envOr("SLURM_PROCID", "?");
  const std::string addr = nodeAddress(node);
  ComposeOptions options;
  options.overrides = readSettings(run_dir);
  const ComposeProject first_look = loadCompose(compose_file, options);
  const ComposeService* mine = first_look.find(service);
  if (!mine) throw LaunchError("--slurm-task " + service + ": no such service in " + compose_file.string());
  const bool master = service == "master", display = service == "display";
  if (master) {
    const ComposeService* c = first_look.find("compositor");
    const std::string run = run_dir.filename().string();  // <job>-<farm>
    const size_t dash = run.rfind('-');
    const int farm = dash == std::string::npos ? 1 : std::atoi(run.c_str() + dash + 1);
    const int base = chooseBasePort(addr, slurmFirstPort(run.substr(0, dash), farm), c ? c->replicas : 0);
    publish(run_dir / "master.endpoint", "tcp://" + addr + ":" + std::to_string(base));
  }
  if (display) publish(run_dir / "display.host", addr);
  options.overrides["TESSERA_ENDPOINTS"] = awaitFile(run_dir / "master.endpoint", "master");
  // Renderers only talk to the master and to compositors (whose addresses it sends them).
  if (service != "renderer") options.overrides["TESSERA_DISPLAY_HOST"] = awaitFile(run_dir / "display.host", "display");
  options.overrides["TESSERA_BIND_HOST"] = addr;
  options.overrides["TESSERA_ADVERTISE_HOST"] = addr;
  const ComposeProject project = loadCompose(compose_file, options);

  LaunchOptions launch_options;
  std::string label = mine->replicas > 1 ? service + "-" + std::to_string(replica) : service;
  label += " (task " + task + " on " + node + ")";
  launch_options.only = LaunchOptions::Only{service, replica, label};
  const int rc = launch(project, launch_options);
  // The farm's success is the display's (its exit leader), whatever srun says of lost tasks.
  if (display && rc == 0) publish(run_dir / "finished", "display");
  if (rc == 0 || rc >= 128) return rc;  // 128+signal: the step is being stopped (scancel)
  if (master || display) {
    // The farm cannot go on without it: end the step (srun then ends non-zero).
    const std::string step = envOr("SLURM_JOB_ID", "") + "." + envOr("SLURM_STEP_ID", "");
    std::cout << "tessera-up | " << label << " is lost: cancelling the farm's job step " << step << std::endl;
    if (std::system(("scancel --quiet '" + step + "'").c_str()) != 0) std::cout << "tessera-up | scancel failed" << std::endl;
    return rc;
  }
  std::cout << "tessera-up | " << label << " is lost; the farm goes on without it" << std::endl;
  return 0;
}

}  // namespace tessera::launcher
