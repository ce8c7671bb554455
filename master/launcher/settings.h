// The farm's TESSERA_* settings as a user gives them (environment, .env, --env), checked
// before anything starts: an error names the variable and the value the user typed, never
// the flag it becomes; relative paths are taken from the user's folder, not the compose
// file's; an unknown TESSERA_* name gets a warning with the closest known one.
#pragma once
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "master/launcher/compose.h"

namespace tessera::launcher {

struct CheckedSettings {
  // Values to pass on instead of the user's (paths made absolute), by variable.
  std::map<std::string, std::string> overrides;
  std::vector<std::string> warnings;
};

// `names`: every variable the user set (any source); `lookup`: its value with the same
// precedence as compose interpolation. Throws LaunchError naming the first bad setting.
CheckedSettings checkSettings(const std::vector<std::string>& names, const VariableLookup& lookup,
                              const std::filesystem::path& user_dir);

// The known name closest to `name` (edit distance at most 3), or "".
std::string closestSetting(const std::string& name);

}  // namespace tessera::launcher
