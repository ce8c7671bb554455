// Compose file -> ComposeProject (see compose.h). Keys that only make sense for containers
// are accepted and ignored; keys Compose does not know are errors naming their path.
#include "master/launcher/compose.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace tessera::launcher {
namespace {

// Service keys that describe the container, not the process: ignored when run locally.
const std::set<std::string, std::less<>> kIgnoredServiceKeys = {
    "annotations", "attach", "blkio_config", "build", "cap_add", "cap_drop", "cgroup",
    "cgroup_parent", "configs", "container_name", "cpu_count", "cpu_percent", "cpu_period",
    "cpu_quota", "cpu_rt_period", "cpu_rt_runtime", "cpu_shares", "cpus", "cpuset",
    "credential_spec", "develop", "device_cgroup_rules", "devices", "dns", "dns_opt",
    "dns_search", "domainname", "driver_opts", "expose", "external_links", "extra_hosts", "gpus",
    "group_add", "healthcheck", "hostname", "image", "init", "ipc", "isolation", "labels",
    "label_file", "links", "logging", "mac_address", "mem_limit", "mem_reservation",
    "mem_swappiness", "memswap_limit", "models", "network_mode", "networks", "oom_kill_disable",
    "oom_score_adj", "pid", "pids_limit", "platform", "ports", "post_start", "pre_stop",
    "privileged", "provider", "pull_policy", "read_only", "runtime", "secrets",
    "security_opt", "shm_size", "stdin_open", "stop_grace_period", "stop_signal", "storage_opt",
    "sysctls", "tmpfs", "tty", "ulimits", "use_api_socket", "user", "userns_mode", "uts",
    "volumes", "volumes_from", "working_dir"};
const std::set<std::string, std::less<>> kIgnoredTopKeys = {"name", "version", "networks",
                                                             "volumes", "configs", "secrets",
                                                             "models"};
const std::set<std::string, std::less<>> kIgnoredDeployKeys = {
    "mode", "endpoint_mode", "labels", "placement", "resources", "restart_policy",
    "rollback_config", "update_config"};

bool isExtension(const std::string& key) { return key.rfind("x-", 0) == 0; }

struct Context {
  std::string file;
  VariableLookup vars;
  std::filesystem::path directory;
  std::vector<std::string>* warnings;

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw ComposeError(file + ": " + where + ": " + what);
  }
  std::string scalar(const YAML::Node& n, const std::string& where) const {
    if (!n.IsScalar()) fail(where, "expected a string");
    return interpolate(n.Scalar(), vars, warnings, file + ": " + where);
  }
  std::vector<std::string> command(const YAML::Node& n, const std::string& where) const {
    if (n.IsNull()) return {};
    if (n.IsScalar()) return splitCommandLine(scalar(n, where), file + ": " + where);
    if (!n.IsSequence()) fail(where, "expected a string or a list of strings");
    std::vector<std::string> argv;
    for (size_t i = 0; i < n.size(); ++i) argv.push_back(scalar(n[i], where + "[" + std::to_string(i) + "]"));
    return argv;
  }
  int integer(const YAML::Node& n, const std::string& where, int lo, int hi) const {
    const std::string s = scalar(n, where);
    size_t used = 0;
    int v = 0;
    try {
      v = std::stoi(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != s.size()) fail(where, "expected an integer, got \"" + s + "\"");
    if (v < lo || v > hi) {
      fail(where, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return v;
  }
  bool boolean(const YAML::Node& n, const std::string& where) const {
    const std::string s = scalar(n, where);
    if (s == "true" || s == "True" || s == "yes") return true;
    if (s == "false" || s == "False" || s == "no") return false;
    fail(where, "expected true or false, got \"" + s + "\"");
  }
};

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ComposeError(path.string() + ": cannot read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void readEnvironment(const Context& cx, const YAML::Node& n, const std::string& where,
                     std::map<std::string, std::string>& env) {
  // A key without a value passes the variable through from the launcher's environment.
  auto passThrough = [&](const std::string& key) {
    if (auto v = cx.vars(key)) env[key] = *v; else env.erase(key);
  };
  if (n.IsMap()) {
    for (const auto& kv : n) {
      const std::string key = kv.first.Scalar();
      if (key.empty()) cx.fail(where, "empty variable name");
      if (kv.second.IsNull()) passThrough(key);
      else env[key] = cx.scalar(kv.second, where + "." + key);
    }
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) {
      const std::string entry = cx.scalar(n[i], where + "[" + std::to_string(i) + "]");
      const size_t eq = entry.find('=');
      if (eq == 0 || entry.empty()) cx.fail(where + "[" + std::to_string(i) + "]", "empty variable name");
      if (eq == std::string::npos) passThrough(entry);
      else env[entry.substr(0, eq)] = entry.substr(eq + 1);
    }
  } else if (!n.IsNull()) {
    cx.fail(where, "expected a map or a list of KEY=VALUE");
  }
}

void readEnvFiles(const Context& cx, const YAML::Node& n, const std::string& where,
                  std::map<std::string, std::string>& env) {
  std::vector<std::pair<std::string, bool>> files;  // path, required
  if (n.IsScalar()) {
    files.emplace_back(cx.scalar(n, where), true);
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) {
      const std::string at = where + "[" + std::to_string(i) + "]";
      if (n[i].IsMap()) {
        if (!n[i]["path"]) cx.fail(at + ".path", "missing");
        files.emplace_back(cx.scalar(n[i]["path"], at + ".path"),
                           !n[i]["required"] || cx.boolean(n[i]["required"], at + ".required"));
      } else {
        files.emplace_back(cx.scalar(n[i], at), true);
      }
    }
  } else {
    cx.fail(where, "expected a path or a list of paths");
  }
  for (const auto& [name, required] : files) {
    const std::filesystem::path path = cx.directory / name;
    if (!std::filesystem::exists(path)) {
      if (required) cx.fail(where, "env file " + path.string() + " does not exist");
      continue;
    }
    for (auto& [k, v] : parseDotEnv(readFile(path), path.string())) env[k] = v;
  }
}

std::vector<std::string> readDependsOn(const Context& cx, const YAML::Node& n, const std::string& where) {
  std::vector<std::string> deps;
  if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) deps.push_back(cx.scalar(n[i], where + "[" + std::to_string(i) + "]"));
  } else if (n.IsMap()) {
    // Conditions (service_healthy, ...) need container health checks; locally the order
    // of starting is all that is kept.
    for (const auto& kv : n) deps.push_back(kv.first.Scalar());
  } else {
    cx.fail(where, "expected a list or a map of service names");
  }
  return deps;
}

// Returns whether deploy.replicas was given (it wins over the legacy `scale`).
bool readDeploy(const Context& cx, const YAML::Node& n, const std::string& where, ComposeService& s) {
  if (!n.IsMap()) cx.fail(where, "expected a map");
  bool replicas = false;
  for (const auto& kv : n) {
    const std::string key = kv.first.Scalar();
    if (key == "replicas") {
      s.replicas = cx.integer(kv.second, where + ".replicas", 0, 1024);
      replicas = true;
    } else if (!kIgnoredDeployKeys.contains(key) && !isExtension(key)) {
      cx.fail(where + "." + key, "unknown key");
    }
  }
  return replicas;
}

bool profileActive(const Context& cx, const YAML::Node& n, const std::string& where) {
  if (!n.IsSequence()) cx.fail(where, "expected a list of profile names");
  const std::string enabled = cx.vars("COMPOSE_PROFILES").value_or("");
  std::set<std::string> active;
  std::stringstream ss(enabled);
  for (std::string p; std::getline(ss, p, ',');) active.insert(p);
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string p = cx.scalar(n[i], where + "[" + std::to_string(i) + "]");
    if (active.contains(p) || active.contains("*")) return true;
  }
  return false;
}

// Returns nullopt for a service whose profiles are not enabled.
std::optional<ComposeService> readService(const Context& cx, const std::string& name, const YAML::Node& n) {
  const std::string where = "services." + name;
  if (!n.IsMap()) cx.fail(where, "expected a map");
  ComposeService s;
  s.name = name;
  std::vector<std::string> entrypoint, command;
  std::optional<std::vector<std::string>> local_command;
  std::optional<bool> leader;
  std::optional<int> scale;
  bool deploy_replicas = false;
  std::map<std::string, std::string> file_env, local_env;
  for (const auto& kv : n) {
    const std::string key = kv.first.Scalar();
    const std::string at = where + "." + key;
    const YAML::Node& v = kv.second;
    if (key == "command") command = cx.command(v, at);
    else if (key == "entrypoint") entrypoint = cx.command(v, at);
    else if (key == "environment") readEnvironment(cx, v, at, s.environment);
    else if (key == "env_file") readEnvFiles(cx, v, at, file_env);
    else if (key == "deploy") deploy_replicas = readDeploy(cx, v, at, s);
    else if (key == "scale") scale = cx.integer(v, at, 0, 1024);
    else if (key == "restart") s.restart = parseRestartPolicy(cx.scalar(v, at), cx.file + ": " + at);
    else if (key == "depends_on") s.depends_on = readDependsOn(cx, v, at);
    else if (key == "profiles") { if (!profileActive(cx, v, at)) return std::nullopt; }
    else if (key == "extends") cx.fail(at, "not supported by tessera-up; write the service out");
    else if (key == "x-tessera") {
      if (!v.IsMap()) cx.fail(at, "expected a map");
      for (const auto& x : v) {
        const std::string xkey = x.first.Scalar();
        if (xkey == "local_command") local_command = cx.command(x.second, at + ".local_command");
        else if (xkey == "local_environment") readEnvironment(cx, x.second, at + ".local_environment", local_env);
        else if (xkey == "exit_leader") leader = cx.boolean(x.second, at + ".exit_leader");
        else cx.fail(at + "." + xkey, "unknown key (known: local_command, local_environment, exit_leader)");
      }
    } else if (!kIgnoredServiceKeys.contains(key) && !isExtension(key)) {
      cx.fail(at, "unknown key");
    }
  }
  if (scale && !deploy_replicas) s.replicas = *scale;
  for (auto& [k, v] : file_env) s.environment.try_emplace(k, v);  // `environment` wins
  for (auto& [k, v] : local_env) s.environment[k] = v;  // and x-tessera.local_environment over it
  if (local_command) {
    s.argv = *local_command;
  } else {
    s.argv = entrypoint;
    s.argv.insert(s.argv.end(), command.begin(), command.end());
  }
  if (s.argv.empty()) {
    cx.fail(where, "no command: set command, entrypoint or x-tessera.local_command "
                   "(an image's default command is unknown without a container engine)");
  }
  s.exit_leader = leader.value_or(name == "display");
  return s;
}

// Dependencies first; among services that are ready, file order is kept.
std::vector<ComposeService> startOrder(const Context& cx, std::vector<ComposeService> services) {
  std::set<std::string> names;
  for (const auto& s : services) names.insert(s.name);
  for (const auto& s : services) {
    for (const auto& d : s.depends_on) {
      if (!names.contains(d)) cx.fail("services." + s.name + ".depends_on", "unknown or disabled service \"" + d + "\"");
    }
  }
  std::vector<ComposeService> ordered;
  std::set<std::string> placed;
  while (!services.empty()) {
    auto ready = std::find_if(services.begin(), services.end(), [&](const ComposeService& s) {
      return std::all_of(s.depends_on.begin(), s.depends_on.end(),
                         [&](const std::string& d) { return placed.contains(d); });
    });
    if (ready == services.end()) {
      std::string cycle;
      for (const auto& s : services) cycle += (cycle.empty() ? "" : ", ") + s.name;
      cx.fail("services", "depends_on cycle among: " + cycle);
    }
    placed.insert(ready->name);
    ordered.push_back(std::move(*ready));
    services.erase(ready);
  }
  return ordered;
}

}  // namespace

const ComposeService* ComposeProject::find(std::string_view service) const {
  for (const auto& s : services) {
    if (s.name == service) return &s;
  }
  return nullptr;
}

ComposeProject parseCompose(const std::string& yaml_text, const std::filesystem::path& directory,
                            const ComposeOptions& options, const std::string& file_label) {
  ComposeProject project;
  project.directory = directory;
  std::map<std::string, std::string> dotenv;
  const std::filesystem::path dotenv_path = directory / ".env";
  if (std::filesystem::exists(dotenv_path)) dotenv = parseDotEnv(readFile(dotenv_path), dotenv_path.string());
  VariableLookup process_env = options.process_env;
  if (!process_env) {
    process_env = [](const std::string& k) -> std::optional<std::string> {
      const char* v = std::getenv(k.c_str());
      return v ? std::optional<std::string>(v) : std::nullopt;
    };
  }
  Context cx;
  cx.file = file_label;
  cx.directory = directory;
  cx.warnings = &project.warnings;
  cx.vars = [&options, process_env, dotenv](const std::string& k) -> std::optional<std::string> {
    if (auto it = options.overrides.find(k); it != options.overrides.end()) return it->second;
    if (auto v = process_env(k)) return v;
    if (auto it = dotenv.find(k); it != dotenv.end()) return it->second;
    return std::nullopt;
  };

  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ComposeError(file_label + ": " + e.what());
  }
  if (!root.IsMap()) throw ComposeError(file_label + ": expected a map at the top level");
  YAML::Node services_node;
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key == "services") services_node = kv.second;
    else if (key == "name") project.name = cx.scalar(kv.second, "name");
    else if (key == "include") cx.fail(key, "not supported by tessera-up");
    else if (!kIgnoredTopKeys.contains(key) && !isExtension(key)) cx.fail(key, "unknown key");
  }
  if (!services_node || !services_node.IsMap() || services_node.size() == 0) {
    cx.fail("services", "expected a non-empty map of services");
  }
  std::vector<ComposeService> services;
  for (const auto& kv : services_node) {
    if (auto s = readService(cx, kv.first.Scalar(), kv.second)) services.push_back(std::move(*s));
  }
  project.services = startOrder(cx, std::move(services));
  if (project.name.empty()) project.name = std::filesystem::absolute(directory).filename().string();
  return project;
}

ComposeProject loadCompose(const std::filesystem::path& file, const ComposeOptions& options) {
  const std::filesystem::path absolute = std::filesystem::absolute(file);
  return parseCompose(readFile(absolute), absolute.parent_path(), options, file.string());
}

}  // namespace tessera::launcher
