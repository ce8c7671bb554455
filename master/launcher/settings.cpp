#include "master/launcher/settings.h"

#include <algorithm>
#include <charconv>
#include <optional>

#include "common/closest.h"
#include "master/launcher/launcher.h"

namespace tessera::launcher {
namespace {

enum class Kind { Free, Int, Word, Path, ExistingFile };

struct Setting {
  const char* name;
  Kind kind;
  long long min = 0, max = 0;  // Int
  const char* words = "";      // Word: accepted values separated by '|'
  const char* meaning = "";    // said after a refused value, so the user knows what to give
};

// Every TESSERA_* variable the farm, its scripts and its tests read.
const Setting kSettings[] = {
    {"TESSERA_SCENE", Kind::ExistingFile},
    {"TESSERA_OUT", Kind::Path},
    {"TESSERA_KEYS", Kind::Path},
    {"TESSERA_METRICS", Kind::Path},
    {"TESSERA_RENDERERS", Kind::Int, 1, 1024, "", "renderer processes"},
    {"TESSERA_COMPOSITORS", Kind::Int, 0, 256, "", "compositor processes (0: a binary-swap farm needs none)"},
    {"TESSERA_FRAMES", Kind::Int, -1, 100000000, "",
     "frames to render; -1: the scene's orbit, 0: interactive until the window closes or Ctrl-C"},
    {"TESSERA_IN_FLIGHT", Kind::Int, 1, 64},
    {"TESSERA_TILES_PER_RENDERER", Kind::Int, 1, 64},
    {"TESSERA_THREADS", Kind::Int, 0, 1024},
    {"TESSERA_CACHE_MB", Kind::Int, 0, 1 << 20, "", "MiB of a time series' steps a renderer holds besides the one shown"},
    {"TESSERA_CODEC", Kind::Word, 0, 0, "none|lzo|lz4|zstd"},
    {"TESSERA_FORMAT", Kind::Word, 0, 0, "rgba16f|rgba8|rgba32f"},
    {"TESSERA_TILING", Kind::Word, 0, 0, "balanced|static"},
    {"TESSERA_COMPOSITING", Kind::Word, 0, 0, "auto|direct-send|binary-swap"},
    {"TESSERA_WINDOW", Kind::Word, 0, 0, "auto|on|off"},
    {"TESSERA_BACKEND", Kind::Word, 0, 0, "cpu|osmesa"},
    {"TESSERA_CURVE", Kind::Word, 0, 0, "auto|on|off"},
    {"TESSERA_PREMULTIPLIED", Kind::Word, 0, 0, "0|1"},
    {"TESSERA_SIMD", Kind::Word, 0, 0, "scalar|avx2|avx512"},
    {"TESSERA_GATHER", Kind::Word, 0, 0, "hardware|lanes"},
    {"TESSERA_LOG", Kind::Word, 0, 0, "trace|debug|info|warn|warning|error|critical|off"},
    {"TESSERA_ENDPOINTS", Kind::Free},
    {"TESSERA_RUN", Kind::Free},
    {"TESSERA_MASTER_HOST", Kind::Free},
    {"TESSERA_DISPLAY_HOST", Kind::Free},
    {"TESSERA_BIND_HOST", Kind::Free},
    {"TESSERA_ADVERTISE_HOST", Kind::Free},
    {"TESSERA_WEB", Kind::Free},        // the display's web view, HOST:PORT
    {"TESSERA_WEB_TOKEN", Kind::Free},
    {"TESSERA_BACKGROUND", Kind::Free},  // the display's --background R,G,B
    {"TESSERA_SERVICE", Kind::Free},  // set by tessera-up for its children
    {"TESSERA_REPLICA", Kind::Free},
    {"TESSERA_FUZZ_SECONDS", Kind::Free},
    {"TESSERA_FUZZ_SEEDS", Kind::Free},
    {"TESSERA_KEEP_TEST_DIRS", Kind::Free},
};


bool isWord(const std::string& value, const std::string& words) {
  size_t start = 0;
  while (true) {
    const size_t bar = words.find('|', start);
    if (words.substr(start, bar - start) == value) return true;
    if (bar == std::string::npos) return false;
    start = bar + 1;
  }
}

std::string describe(const Setting& s) {
  switch (s.kind) {
    case Kind::Int:
      return "a whole number from " + std::to_string(s.min) + " to " + std::to_string(s.max) +
             (*s.meaning ? std::string(" (") + s.meaning + ")" : "");
    case Kind::Word: {
      std::string w = s.words;
      std::replace(w.begin(), w.end(), '|', ',');
      return "one of " + w;
    }
    default: return "";
  }
}

// The problem with `value`, or "" when it is fine.
std::string problem(const Setting& s, const std::string& value) {
  if (s.kind == Kind::Int) {
    long long v = 0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc() || end != value.data() + value.size() || v < s.min || v > s.max)
      return "expected " + describe(s);
  }
  if (s.kind == Kind::Word && !isWord(value, s.words)) return "expected " + describe(s);
  return "";
}

}  // namespace

std::string closestSetting(const std::string& name) {
  std::vector<std::string> names;
  for (const Setting& s : kSettings) names.push_back(s.name);
  return closestName(name, names);
}

CheckedSettings checkSettings(const std::vector<std::string>& names, const VariableLookup& lookup,
                              const std::filesystem::path& user_dir) {
  CheckedSettings out;
  for (const std::string& name : names) {
    if (name.rfind("TESSERA_", 0) != 0) continue;
    const auto known = std::find_if(std::begin(kSettings), std::end(kSettings),
                                    [&](const Setting& s) { return name == s.name; });
    if (known == std::end(kSettings)) {
      const std::string near = closestSetting(name);
      out.warnings.push_back(name + " is not a Tessera setting (ignored)" +
                             (near.empty() ? "" : "; did you mean " + near + "?"));
      continue;
    }
    const std::optional<std::string> value = lookup(name);
    if (!value || value->empty()) continue;  // unset or empty: the compose file's default
    if (std::string why = problem(*known, *value); !why.empty()) throw LaunchError(name + "=" + *value + ": " + why);
    if (known->kind != Kind::Path && known->kind != Kind::ExistingFile) continue;
    const std::filesystem::path p = std::filesystem::path(*value);
    const std::filesystem::path absolute = p.is_absolute() ? p : (user_dir / p).lexically_normal();
    // A file, or a folder that the program reads (a DICOM series or TIFF stack given as the scene).
    if (known->kind == Kind::ExistingFile && !std::filesystem::exists(absolute))
      throw LaunchError(name + "=" + *value + ": no such file or folder (looked for " + absolute.string() + ")");
    if (!p.is_absolute()) out.overrides[name] = absolute.string();
  }
  return out;
}

}  // namespace tessera::launcher
