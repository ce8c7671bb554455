// The scene parser's helpers (scene.cpp, scene_volume.cpp): strict YAML with errors naming
// the file and the key path. Internal to common/.
#pragma once
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

#include "common/closest.h"
#include "common/scene.h"

namespace tessera::detail {

// Carries the file name so every error starts with it.
class Parser {
 public:
  Parser(std::string file, std::string base) : file_(std::move(file)), base_(std::move(base)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& msg) const {
    throw SceneError(file_ + ": " + (path.empty() ? "" : path + ": ") + msg);
  }

  static std::string describe(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + n.Scalar() + "'";
    if (n.IsSequence()) return n.size() == 0 ? "an empty list" : "a list of " + std::to_string(n.size());
    if (n.IsMap()) return "a map";
    return "nothing";
  }

  void checkKeys(const YAML::Node& n, const std::string& path, std::initializer_list<const char*> allowed) const {
    if (!n.IsMap()) fail(path, "expected a map, got " + describe(n));
    for (const auto& kv : n) {
      std::string k = kv.first.Scalar();
      bool ok = false;
      for (const char* a : allowed) ok = ok || k == a;
      if (!ok) {
        const std::vector<std::string> names(allowed.begin(), allowed.end());
        std::string list, near = closestName(k, names);
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(join(path, k), "unknown key" + (near.empty() ? "" : "; did you mean " + near + "?") + " (allowed: " + list + ")");
      }
    }
  }

  static std::string join(const std::string& path, const std::string& k) { return path.empty() ? k : path + "." + k; }

  YAML::Node require(const YAML::Node& n, const std::string& path, const char* key) const {
    YAML::Node c = n[key];
    if (!c) fail(join(path, key), "missing required key");
    return c;
  }

  double number(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path, "expected a number, got " + describe(n));
    double v;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(path, "expected a number, got " + describe(n));
    }
    if (!std::isfinite(v)) fail(path, "expected a finite number, got " + describe(n));
    return v;
  }

  long long integer(const YAML::Node& n, const std::string& path, long long lo, long long hi) const {
    if (!n.IsScalar()) fail(path, "expected an integer, got " + describe(n));
    long long v;
    try {
      v = n.as<long long>();
    } catch (const YAML::Exception&) {
      fail(path, "expected an integer, got " + describe(n));
    }
    if (v < lo || v > hi)
      fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + std::to_string(v));
    return v;
  }

  bool boolean(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path, "expected true or false, got " + describe(n));
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(path, "expected true or false, got " + describe(n));
    }
  }

  std::string string(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path, "expected a string, got " + describe(n));
    return n.Scalar();
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& path, size_t count) const {
    if (!n.IsSequence() || n.size() != count)
      fail(path, "expected a list of " + std::to_string(count) + " numbers, got " + describe(n));
    std::vector<double> out;
    for (size_t i = 0; i < count; ++i) out.push_back(number(n[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }

  Vec3 vec3(const YAML::Node& n, const std::string& path) const {
    auto v = numbers(n, path, 3);
    return {v[0], v[1], v[2]};
  }

  std::array<double, 3> spacing(const YAML::Node& n, const std::string& path) const {
    auto v = numbers(n, path, 3);
    const std::array<double, 3> sp{v[0], v[1], v[2]};
    if (std::string p = spacingProblem(sp); !p.empty()) fail(path, p);
    return sp;
  }

  // "" for a regular file; else "file not found: PATH" or "PATH is a directory, not a regular file".
  static std::string fileProblem(const std::string& file) {
    const std::string why = notRegularFile(file);
    if (why.empty()) return "";
    return why == "file not found" ? why + ": " + file : file + " " + why;
  }

  // scene_volume.cpp: `volume:` (and its series) and `time:`.
  std::variant<RawVolumeSpec, GeneratorSpec> volume(const YAML::Node& n, TimeSeries& series) const;
  RawVolumeSpec volumeFile(const YAML::Node& n, const std::string& file, TimeSeries& series) const;
  RawVolumeSpec rawFile(const YAML::Node& n, const std::string& file) const;
  TimeSeries seriesFiles(const YAML::Node& n) const;
  Playback playback(const YAML::Node& n, int steps) const;
  std::string resolve(const std::string& f) const {
    std::filesystem::path p(f);
    return (p.is_relative() ? std::filesystem::path(base_) / p : p).lexically_normal().string();
  }
  // The keys a scene may set for any volume file.
  void spacingAndRange(const YAML::Node& n, RawVolumeSpec& s) const {
    if (n["spacing"]) s.spacing = spacing(n["spacing"], "volume.spacing"), s.spacing_given = true;
    if (n["range"]) {
      auto r = numbers(n["range"], "volume.range", 2);
      if (!(r[0] < r[1])) fail("volume.range", "expected [min, max] with min < max");
      s.has_range = true;
      s.range = {r[0], r[1]};
    }
  }
  TransferFunction transferFunction(const YAML::Node& n) const;
  Camera camera(const YAML::Node& n) const;
  Quality quality(const YAML::Node& n) const;
  Orbit orbit(const YAML::Node& n) const;
  MeshSpec mesh(const YAML::Node& n, bool has_volume) const;
  Antialiasing antialiasing(const YAML::Node& n) const;
  Shading shading(const YAML::Node& n) const;
  Crop crop(const YAML::Node& n) const;
  ValueWindow window(const YAML::Node& n) const;

  std::string file_, base_;
};

}  // namespace tessera::detail
