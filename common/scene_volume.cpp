// The scene's `volume:` (a generator, a file, or a series of files) and `time:` keys.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include "common/io/volume_files.h"
#include "common/scene_parser.h"

namespace tessera::detail {
namespace {

constexpr int kMaxSteps = 1000000;

// A printf pattern with exactly one integer conversion (%d, %i or %u, optionally zero-padded
// with a width, e.g. %04d); "%%" is a literal percent. "" when fine, else what is wrong.
std::string patternProblem(const std::string& p) {
  int conversions = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i] != '%') continue;
    if (i + 1 < p.size() && p[i + 1] == '%') {
      ++i;
      continue;
    }
    size_t j = i + 1;
    while (j < p.size() && (std::isdigit((unsigned char)p[j]) || p[j] == '0')) ++j;
    if (j >= p.size() || (p[j] != 'd' && p[j] != 'i' && p[j] != 'u') || j - i > 4)
      return "'" + p + "': expected one integer conversion such as %d or %04d, found '" + p.substr(i, j - i + 1) + "'";
    ++conversions;
    i = j;
  }
  if (conversions != 1) return "'" + p + "' has " + std::to_string(conversions) + " integer conversions; give exactly one (e.g. t%04d.raw)";
  return "";
}

std::string formatted(const std::string& pattern, long long i) {
  char buf[4096];
  std::snprintf(buf, sizeof buf, pattern.c_str(), (int)i);  // checked by patternProblem
  return buf;
}

}  // namespace

std::variant<RawVolumeSpec, GeneratorSpec> Parser::volume(const YAML::Node& n, TimeSeries& series) const {
  checkKeys(n, "volume", {"file", "series", "dims", "type", "spacing", "range", "generator"});
  if (n["generator"]) {
    if (n["file"] || n["series"] || n["dims"] || n["type"] || n["range"])
      fail("volume", "give either generator or file/series/dims/type/range, not both");
    YAML::Node g = n["generator"];
    checkKeys(g, "volume.generator", {"name", "size", "seed", "steps"});
    GeneratorSpec s;
    s.name = string(require(g, "volume.generator", "name"), "volume.generator.name");
    if (!isGeneratorName(s.name))
      fail("volume.generator.name", "unknown generator '" + s.name + "' (" + generatorNames() + ")");
    s.size = g["size"] ? (int)integer(g["size"], "volume.generator.size", 2, 2048) : 256;
    s.seed = g["seed"] ? (uint32_t)integer(g["seed"], "volume.generator.seed", 0, 0xffffffffll) : 1;
    if (n["spacing"]) s.spacing = spacing(n["spacing"], "volume.spacing");
    if (g["steps"] && !isTimeGenerator(s.name))
      fail("volume.generator.steps", "'" + s.name + "' does not change over time (time-varying: moving-blobs)");
    if (g["steps"]) series.steps = (int)integer(g["steps"], "volume.generator.steps", 1, kMaxSteps);
    return s;
  }
  if (n["file"] && n["series"]) fail("volume", "give either file (one volume, or a 4-D file) or series, not both");
  if (n["series"]) {
    series = seriesFiles(n["series"]);
    return volumeFile(n, series.files.front(), series);
  }
  return volumeFile(n, resolve(string(require(n, "volume", "file"), "volume.file")), series);
}

// `series:` a printf pattern with first and last, a list of files, or a ParaView .series
// file. Only names are made here: no file but the first is opened (the last is looked for,
// so a pattern with the wrong range, or a list with a typo at its end, fails now), whatever
// the number of steps.
TimeSeries Parser::seriesFiles(const YAML::Node& n) const {
  TimeSeries t;
  std::string last_key, last_at;  // a list's or a .series file's last step, stat'ed below
  if (n.IsMap()) {
    checkKeys(n, "volume.series", {"pattern", "first", "last"});
    // Checked and formatted as written, then joined to the scene's folder: a '%' in the
    // folder's name is not a conversion.
    const std::string pattern = string(require(n, "volume.series", "pattern"), "volume.series.pattern");
    if (std::string why = patternProblem(pattern); !why.empty()) fail("volume.series.pattern", why);
    const long long first = integer(require(n, "volume.series", "first"), "volume.series.first", 0, 999999999);
    const long long last = integer(require(n, "volume.series", "last"), "volume.series.last", first, first + kMaxSteps - 1);
    for (long long i = first; i <= last; ++i) t.files.push_back(resolve(formatted(pattern, i)));
    std::string folder = std::filesystem::absolute(base_).lexically_normal().string();
    for (size_t at = folder.find('%'); at != std::string::npos; at = folder.find('%', at + 2)) folder.insert(at, "%");
    t.pattern = std::filesystem::path(pattern).is_relative() ? (std::filesystem::path(folder) / pattern).lexically_normal().string()
                                                             : pattern;
    t.first = first;
    for (const std::string* f : {&t.files.front(), &t.files.back()})
      if (std::string m = fileProblem(*f); !m.empty()) fail("volume.series.pattern", m + " (pattern " + pattern + ")");
  } else if (n.IsSequence()) {
    if (n.size() == 0) fail("volume.series", "an empty list: give at least one file");
    for (size_t i = 0; i < n.size(); ++i) t.files.push_back(resolve(string(n[i], "volume.series[" + std::to_string(i) + "]")));
    last_key = "volume.series[" + std::to_string(n.size() - 1) + "]";
  } else {
    // ParaView's file series: {"file-series-version": "1.0", "files": [{"name": ..., "time": ...}, ...]}
    const std::string file = resolve(string(n, "volume.series"));
    if (std::string m = fileProblem(file); !m.empty()) fail("volume.series", m);
    std::ifstream in(file, std::ios::binary);
    const auto j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("files") || !j["files"].is_array())
      fail("volume.series", file + ": not a .series file (JSON with a \"files\" list of {\"name\", \"time\"})");
    const std::filesystem::path dir = std::filesystem::path(file).parent_path();
    for (const auto& e : j["files"]) {
      const std::string at = file + ": files[" + std::to_string(t.files.size()) + "]";
      if (!e.is_object() || !e.contains("name") || !e["name"].is_string() || !e.contains("time") || !e["time"].is_number())
        fail("volume.series", at + ": expected {\"name\": string, \"time\": number}");
      const double time = e["time"].get<double>();
      if (!t.times.empty() && !(time > t.times.back()))
        fail("volume.series", at + ": time " + std::to_string(time) + " is not after the previous step's " + std::to_string(t.times.back()));
      const std::filesystem::path name(e["name"].get<std::string>());
      t.files.push_back((name.is_relative() ? dir / name : name).lexically_normal().string());
      t.times.push_back(time);
    }
    if (t.files.empty()) fail("volume.series", file + ": the files list is empty");
    last_key = "volume.series", last_at = file + ": files[" + std::to_string(t.files.size() - 1) + "]: ";
  }
  if (t.files.size() > (size_t)kMaxSteps) fail("volume.series", "more than " + std::to_string(kMaxSteps) + " steps");
  // A folder a step would be scanned by every process at every step. A pattern's steps are
  // one form: its ends tell (a stat per step made a 1,000,000-step pattern start in seconds).
  const std::vector<std::string> ends{t.files.front(), t.files.back()};
  for (const std::string& f : t.pattern.empty() ? t.files : ends) {
    std::error_code no_throw;
    const VolumeFormat fmt = volumeFormatOf(f);
    if (fmt == VolumeFormat::Dicom || (fmt == VolumeFormat::Tiff && std::filesystem::is_directory(f, no_throw)))
      fail("volume.series", f + ": a " + (fmt == VolumeFormat::Dicom ? "DICOM series" : "folder of TIFF slices") +
                                " cannot be a time step; make each step one file (a multi-page TIFF, NIfTI or NRRD)");
  }
  // The last step's file is stat'ed now too, as a pattern's is (the others when read).
  if (!last_key.empty())
    if (std::string m = fileProblem(t.files.back()); !m.empty()) fail(last_key, last_at + m);
  t.steps = (int)t.files.size();
  return t;
}

// A volume file (or a series' first step): a NIfTI or NRRD header gives dims, type and
// spacing (and a time axis); a raw file needs them in the scene. The scene may set spacing
// and range.
RawVolumeSpec Parser::volumeFile(const YAML::Node& n, const std::string& file, TimeSeries& series) const {
  const std::string key = series.files.empty() ? "volume.file" : "volume.series";
  if (volumeFormatOf(file) == VolumeFormat::Raw) return rawFile(n, file);
  std::error_code no_throw;
  const bool folder = std::filesystem::is_directory(file, no_throw);
  if (folder && (n["dims"] || n["type"]))
    fail(key, file + " is a directory: read as a DICOM series or a TIFF stack, whose headers give dims and type (leave "
                     "them out), or name the raw file");
  for (const char* k : {"dims", "type"})
    if (n[k]) fail(std::string("volume.") + k, std::string("comes from the header of ") + file + "; leave it out");
  if (std::string m = folder ? "" : fileProblem(file); !m.empty()) fail(key, m);
  RawVolumeSpec s;
  int steps = 1;
  try {
    s = readVolumeHeader(file, series.files.empty() ? &steps : nullptr);  // a series of 4-D files is refused
  } catch (const std::exception& e) {
    fail(key, e.what());
  }
  if (steps > 1) {
    series.steps = steps;
    series.step_bytes = (uint64_t)s.dims[0] * s.dims[1] * s.dims[2] * voxelTypeSize(s.type);
    // Every step's end, with one stat now (a compressed file's size says nothing).
    std::error_code ec;
    const uintmax_t have = std::filesystem::file_size(s.samples(), ec);
    const uintmax_t need = s.offset + (uintmax_t)steps * series.step_bytes;
    if (!s.gzip && !ec && have < need)
      fail(key, s.samples() + " has " + std::to_string(have) + " bytes but " + std::to_string(steps) +
                    " time steps of " + std::to_string(series.step_bytes) + " bytes" +
                    (s.offset ? " after " + std::to_string(s.offset) + " bytes of header" : "") + " need " +
                    std::to_string(need));
  }
  spacingAndRange(n, s);
  if (std::string p = spacingProblem(s.spacing); !p.empty() && !n["spacing"])
    fail(key, fmt::format("{}: the header's spacing [{:.7g}, {:.7g}, {:.7g}]: {}; give volume.spacing: [x, y, z] to "
                          "replace it",
                          file, s.spacing[0], s.spacing[1], s.spacing[2], p));
  return s;
}

RawVolumeSpec Parser::rawFile(const YAML::Node& n, const std::string& file) const {
  RawVolumeSpec s;
  s.file = file;
  YAML::Node d = require(n, "volume", "dims");
  if (!d.IsSequence() || d.size() != 3) fail("volume.dims", "expected a list of 3 integers, got " + describe(d));
  for (int i = 0; i < 3; ++i) s.dims[i] = (int)integer(d[i], "volume.dims[" + std::to_string(i) + "]", 1, 65536);
  std::string t = string(require(n, "volume", "type"), "volume.type");
  if (auto type = voxelTypeFromName(t)) s.type = *type;
  else fail("volume.type", "expected uint8, int8, uint16, int16, uint32, int32, float32 or float64, got '" + t + "'");
  // No memory check here: a farm's renderers each load only their bricks, so a volume
  // bigger than this machine is a valid scene; a process that loads too much says so then.
  spacingAndRange(n, s);
  // Cheap checks now (a stat), so a bad file fails at startup rather than in a renderer.
  const std::string key = n["series"] ? "volume.series" : "volume.file";
  if (std::string m = fileProblem(s.file); !m.empty()) fail(key, m);
  std::error_code ec;
  uintmax_t have = std::filesystem::file_size(s.file, ec);
  uintmax_t need = (uintmax_t)s.dims[0] * s.dims[1] * s.dims[2] * voxelTypeSize(s.type);
  const uintmax_t slice = (uintmax_t)s.dims[0] * s.dims[1] * voxelTypeSize(s.type);  // what z can fix
  if (ec || have != need)
    fail(key, s.file + " has " + std::to_string(have) + " bytes but dims x type size need " + std::to_string(need) +
                  " bytes; " +
                  (!ec && have > 0 && have % slice == 0 ? "dims [" + std::to_string(s.dims[0]) + ", " +
                   std::to_string(s.dims[1]) + ", " + std::to_string(have / slice) + "] would match" : "check dims and type"));
  return s;
}

// `time: {play, stride, mode, step}` for a volume of `steps` time steps.
Playback Parser::playback(const YAML::Node& n, int steps) const {
  checkKeys(n, "time", {"play", "stride", "mode", "step"});
  Playback p;
  if (n["play"]) p.play = boolean(n["play"], "time.play");
  if (n["stride"]) p.stride = (int)integer(n["stride"], "time.stride", -kMaxSteps, kMaxSteps);
  if (p.stride == 0) fail("time.stride", "must not be 0 (negative plays backwards)");
  if (n["step"]) p.step = (int)integer(n["step"], "time.step", 0, steps - 1);
  if (n["mode"]) {
    const std::string m = string(n["mode"], "time.mode");
    if (m == "loop") p.mode = Playback::Mode::Loop;
    else if (m == "once") p.mode = Playback::Mode::Once;
    else if (m == "swing") p.mode = Playback::Mode::Swing;
    else fail("time.mode", "expected loop, once or swing, got '" + m + "'");
  }
  return p;
}

}  // namespace tessera::detail
