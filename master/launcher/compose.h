// Reads a Compose-specification file (compose.yaml) into the plain description the local
// launcher (tessera-up) needs: per service argv, environment, replicas and start order.
// Pure functions; not tied to any process state except the optional process environment.
#pragma once
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tessera::launcher {

// Thrown for every invalid compose file; the message names the file and key path.
class ComposeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Compose `restart:` policy. Locally "unless-stopped" is "always" (nothing stops a single
// service by hand); max_retries (on-failure:N) counts restarts, 0 = no limit.
struct RestartPolicy {
  enum class Mode { No, OnFailure, Always, UnlessStopped };
  Mode mode = Mode::No;
  int max_retries = 0;
  // Whether a child that ended with `status` (a waitpid status) is started again.
  bool restartsAfter(int status) const;
  std::string text() const;  // as written in compose.yaml: "on-failure:3"
  bool operator==(const RestartPolicy&) const = default;
};

// Parses no | on-failure[:N] | always | unless-stopped; throws ComposeError naming `where`.
RestartPolicy parseRestartPolicy(const std::string& value, const std::string& where);

struct ComposeService {
  std::string name;
  // entrypoint + command, or x-tessera.local_command (which replaces both: container
  // entrypoints name image paths that do not exist on the host).
  std::vector<std::string> argv;
  // Only the service's own variables: env_file < environment < x-tessera.local_environment
  // (for values that differ between containers and a local run, e.g. endpoints);
  // the launcher adds them to its own environment plus TESSERA_SERVICE/TESSERA_REPLICA.
  std::map<std::string, std::string> environment;
  int replicas = 1;
  std::vector<std::string> depends_on;
  bool exit_leader = false;  // its exit 0 ends the farm successfully
  RestartPolicy restart;
  bool operator==(const ComposeService&) const = default;
};

struct ComposeProject {
  std::string name;                   // `name:` or the folder name
  std::filesystem::path directory;    // the compose file's folder; children run there
  std::vector<ComposeService> services;  // in start order (dependencies first)
  std::vector<std::string> warnings;     // e.g. unset variables defaulted to ""
  const ComposeService* find(std::string_view service) const;
};

// Returns the value of a variable, or nullopt when it is unset (not the same as empty).
using VariableLookup = std::function<std::optional<std::string>(const std::string&)>;

// Compose interpolation: $VAR ${VAR} ${VAR:-d} ${VAR-d} ${VAR:?e} ${VAR?e} ${VAR:+a}
// ${VAR+a}, $$ -> $; defaults/alternatives may themselves contain variables. An unset
// plain variable becomes "" and a warning is appended. `where` (a key path) is put in
// error and warning messages. Throws ComposeError.
std::string interpolate(std::string_view text, const VariableLookup& lookup,
                        std::vector<std::string>* warnings, const std::string& where);

// Splits a command string like a POSIX shell would split words (no expansion):
// whitespace separates, '...' is literal, "..." honours \" \\ \$ \`, \x escapes x.
// Throws ComposeError on an unterminated quote.
std::vector<std::string> splitCommandLine(std::string_view line, const std::string& where);

// Parses a .env / env_file: KEY=VALUE lines, # comments, optional `export `, quoted values.
std::map<std::string, std::string> parseDotEnv(std::string_view text, const std::string& where);

struct ComposeOptions {
  // Variables given with --env: win over the process environment and .env.
  std::map<std::string, std::string> overrides;
  // Process environment lookup; default reads getenv. Tests substitute a fixed map.
  VariableLookup process_env;
};

// Parses compose YAML text; `directory` is where .env and env_file paths are looked up.
ComposeProject parseCompose(const std::string& yaml_text, const std::filesystem::path& directory,
                            const ComposeOptions& options, const std::string& file_label);

// Reads `file` (and the .env beside it) and parses it.
ComposeProject loadCompose(const std::filesystem::path& file, const ComposeOptions& options);

// Shell-quotes argv for display (dry-run, logs).
std::string quoteCommand(const std::vector<std::string>& argv);

}  // namespace tessera::launcher
