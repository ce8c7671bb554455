// Scene file parser (scenes/README.md): strict YAML with errors naming file and key path.
#include "common/scene.h"

#include "common/closest.h"
#include "common/io/volume_files.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <tuple>

namespace tessera {

Camera Orbit::at(const Camera& base, int frame) const {
  if (frames <= 1) return base;
  return base.orbited(axis, 360.0 * frame / frames);
}

namespace {

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

  std::variant<RawVolumeSpec, GeneratorSpec> volume(const YAML::Node& n) const;
  RawVolumeSpec volumeFile(const YAML::Node& n, const std::string& file) const;
  // The keys a scene may set for any volume file.
  void spacingAndRange(const YAML::Node& n, RawVolumeSpec& s) const {
    if (n["spacing"]) s.spacing = spacing(n["spacing"], "volume.spacing");
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

  std::string file_, base_;
};

std::variant<RawVolumeSpec, GeneratorSpec> Parser::volume(const YAML::Node& n) const {
  checkKeys(n, "volume", {"file", "dims", "type", "spacing", "range", "generator"});
  if (n["generator"]) {
    if (n["file"] || n["dims"] || n["type"] || n["range"])
      fail("volume", "give either generator or file/dims/type/range, not both");
    YAML::Node g = n["generator"];
    checkKeys(g, "volume.generator", {"name", "size", "seed"});
    GeneratorSpec s;
    s.name = string(require(g, "volume.generator", "name"), "volume.generator.name");
    if (!isGeneratorName(s.name))
      fail("volume.generator.name", "unknown generator '" + s.name + "' (" + generatorNames() + ")");
    s.size = g["size"] ? (int)integer(g["size"], "volume.generator.size", 2, 2048) : 256;
    s.seed = g["seed"] ? (uint32_t)integer(g["seed"], "volume.generator.seed", 0, 0xffffffffll) : 1;
    if (n["spacing"]) s.spacing = spacing(n["spacing"], "volume.spacing");
    return s;
  }
  RawVolumeSpec s;
  std::string f = string(require(n, "volume", "file"), "volume.file");
  std::filesystem::path p(f);
  s.file = (p.is_relative() ? std::filesystem::path(base_) / p : p).lexically_normal().string();
  if (volumeFormatOf(s.file) != VolumeFormat::Raw) return volumeFile(n, s.file);
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
  if (std::string m = fileProblem(s.file); !m.empty()) fail("volume.file", m);
  std::error_code ec;
  uintmax_t have = std::filesystem::file_size(s.file, ec);
  uintmax_t need = (uintmax_t)s.dims[0] * s.dims[1] * s.dims[2] * voxelTypeSize(s.type);
  const uintmax_t slice = (uintmax_t)s.dims[0] * s.dims[1] * voxelTypeSize(s.type);  // what z can fix
  if (ec || have != need)
    fail("volume.file", s.file + " has " + std::to_string(have) + " bytes but dims x type size need " +
                            std::to_string(need) + " bytes; " +
                            (!ec && have > 0 && have % slice == 0 ? "dims [" + std::to_string(s.dims[0]) + ", " +
                             std::to_string(s.dims[1]) + ", " + std::to_string(have / slice) + "] would match" : "check dims and type"));
  return s;
}

// A NIfTI or NRRD file: its header gives dims, type and spacing; the scene may set spacing
// and range.
RawVolumeSpec Parser::volumeFile(const YAML::Node& n, const std::string& file) const {
  for (const char* key : {"dims", "type"})
    if (n[key]) fail(std::string("volume.") + key, std::string("comes from the header of ") + file + "; leave it out");
  if (std::string m = fileProblem(file); !m.empty()) fail("volume.file", m);
  RawVolumeSpec s;
  try {
    s = readVolumeHeader(file);
  } catch (const std::exception& e) {
    fail("volume.file", e.what());
  }
  spacingAndRange(n, s);
  return s;
}

TransferFunction Parser::transferFunction(const YAML::Node& n) const {
  if (n.IsScalar()) {
    try {
      return transferFunctionPreset(n.Scalar());
    } catch (const std::invalid_argument& e) {
      fail("transfer_function", e.what());
    }
  }
  if (!n.IsSequence() || n.size() == 0)
    fail("transfer_function", "expected a preset name or a non-empty list of [s, r, g, b, a], got " + describe(n));
  std::vector<TfPoint> pts;
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string path = "transfer_function[" + std::to_string(i) + "]";
    auto v = numbers(n[i], path, 5);
    for (size_t k = 0; k < 5; ++k)
      if (v[k] < 0 || v[k] > 1)
        fail(path + "[" + std::to_string(k) + "]", "must be in [0, 1], got " + describe(n[i][k]));
    if (i > 0 && v[0] < pts.back().s)
      fail(path, "scalar " + describe(n[i][0]) + " is less than the previous point's; points must be sorted");
    pts.push_back({v[0], v[1], v[2], v[3], v[4]});
  }
  try {
    return TransferFunction(std::move(pts));
  } catch (const std::invalid_argument& e) {  // unreachable after the checks above; kept as a guard
    fail("transfer_function", e.what());
  }
}

Camera Parser::camera(const YAML::Node& n) const {
  checkKeys(n, "camera", {"eye", "target", "up", "fov", "orthographic", "height"});
  Camera c;
  c.eye = vec3(require(n, "camera", "eye"), "camera.eye");
  c.target = vec3(require(n, "camera", "target"), "camera.target");
  if (n["up"]) c.up = vec3(n["up"], "camera.up");
  if (n["orthographic"]) c.orthographic = boolean(n["orthographic"], "camera.orthographic");
  if (n["fov"]) c.fov = number(n["fov"], "camera.fov");
  if (c.orthographic) c.height = number(require(n, "camera", "height"), "camera.height");
  else if (n["height"]) fail("camera.height", "only valid with orthographic: true");
  // Before validate(): out-of-range values would otherwise surface as a misleading "parallel".
  if (auto [key, what] = cameraProblem(c); !what.empty()) fail(key, what);
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    fail("", e.what());  // its message already starts with "camera: "
  }
  return c;
}

Quality Parser::quality(const YAML::Node& n) const {
  if (n.IsScalar()) {
    try {
      return namedQuality(n.Scalar());
    } catch (const std::invalid_argument& e) {
      fail("quality", e.what());
    }
  }
  checkKeys(n, "quality", {"step", "early_termination", "skip_empty"});
  Quality q = namedQuality(QualityName::Default);
  q.name = QualityName::Custom;
  if (n["step"]) {
    q.step = number(n["step"], "quality.step");
    if (std::string p = stepProblem(q.step); !p.empty()) fail("quality.step", p);
  }
  if (n["early_termination"]) {
    q.early_termination = number(n["early_termination"], "quality.early_termination");
    if (!(q.early_termination > 0)) fail("quality.early_termination", "must be > 0 (values > 1 disable it)");
  }
  if (n["skip_empty"]) q.skip_empty = boolean(n["skip_empty"], "quality.skip_empty");
  return q;
}

Orbit Parser::orbit(const YAML::Node& n) const {
  checkKeys(n, "orbit", {"frames", "axis"});
  Orbit o;
  if (n["frames"]) o.frames = (int)integer(n["frames"], "orbit.frames", 1, 1000000);
  if (n["axis"]) {
    o.axis = vec3(n["axis"], "orbit.axis");
    if (!(length(o.axis) > 0)) fail("orbit.axis", "must be non-zero");
  }
  return o;
}

MeshSpec Parser::mesh(const YAML::Node& n, bool has_volume) const {
  MeshSpec m;
  if (n.IsScalar()) {
    std::filesystem::path p(n.Scalar());
    m.file = (p.is_relative() ? std::filesystem::path(base_) / p : p).lexically_normal().string();
    if (std::string why = fileProblem(m.file); !why.empty()) fail("mesh", why);
    return m;
  }
  checkKeys(n, "mesh", {"isosurface"});
  YAML::Node iso = require(n, "mesh", "isosurface");
  checkKeys(iso, "mesh.isosurface", {"of", "level"});
  if (string(require(iso, "mesh.isosurface", "of"), "mesh.isosurface.of") != "volume")
    fail("mesh.isosurface.of", "expected 'volume'");
  if (!has_volume) fail("mesh.isosurface", "needs the scene's volume: key");
  if (iso["level"]) m.level = number(iso["level"], "mesh.isosurface.level");
  return m;
}

Antialiasing Parser::antialiasing(const YAML::Node& n) const {
  checkKeys(n, "antialiasing", {"method", "samples", "sigma"});
  Antialiasing a;
  try {
    a.method = parseAaMethod(string(require(n, "antialiasing", "method"), "antialiasing.method"));
  } catch (const std::invalid_argument& e) {
    fail("antialiasing.method", e.what());
  }
  if (a.method == AaMethod::Msaa) a.samples = 4;
  if (a.method == AaMethod::Ssaa) a.samples = 2;
  if (n["samples"]) {
    if (a.method == AaMethod::Msaa) a.samples = (int)integer(n["samples"], "antialiasing.samples", 1, 4);
    else if (a.method == AaMethod::Ssaa) a.samples = (int)integer(n["samples"], "antialiasing.samples", 1, 8);
    else fail("antialiasing.samples", "only valid with method msaa or ssaa");
    if (a.method == AaMethod::Msaa && a.samples == 3) fail("antialiasing.samples", "msaa takes 1, 2 or 4 samples");
  }
  if (n["sigma"]) {
    if (a.method != AaMethod::Fft) fail("antialiasing.sigma", "only valid with method fft");
    a.sigma = number(n["sigma"], "antialiasing.sigma");
    if (!(a.sigma > 0 && a.sigma <= 64)) fail("antialiasing.sigma", "must be in (0, 64] pixels");
  }
  return a;
}

// `shading: true` (VTK's defaults) or a map of coefficients; each coefficient in [0, 1], so a
// lit colour stays within what the transfer function can give (shininess 1..128 as OpenGL's).
Shading Parser::shading(const YAML::Node& n) const {
  Shading sh;
  sh.on = n.IsScalar() ? boolean(n, "shading") : true;
  if (n.IsScalar()) return sh;
  checkKeys(n, "shading", {"ambient", "diffuse", "specular", "shininess"});
  const std::tuple<const char*, double*, int, int> keys[] = {
      {"ambient", &sh.ambient, 0, 1}, {"diffuse", &sh.diffuse, 0, 1}, {"specular", &sh.specular, 0, 1},
      {"shininess", &sh.shininess, 1, 128}};
  for (const auto& [key, value, lo, hi] : keys) {
    const std::string path = std::string("shading.") + key;
    if (n[key]) *value = number(n[key], path);
    if (!(*value >= lo && *value <= hi))
      fail(path, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return sh;
}

}  // namespace

Scene parseScene(const std::string& yaml_text, const std::string& base_dir, const std::string& name_for_errors) {
  Parser p(name_for_errors, base_dir);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    p.fail("", "YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) p.fail("", "expected a map of scene keys at the top level");
  p.checkKeys(root, "",
              {"volume", "transfer_function", "camera", "image", "quality", "orbit", "mesh", "light", "antialiasing",
               "shading"});
  Scene s;
  s.path = name_for_errors;
  s.quality = namedQuality(QualityName::Default);
  // A mesh scene needs a volume only for its isosurface, and a transfer function not at all.
  const bool is_mesh = (bool)root["mesh"];
  s.has_volume = !is_mesh || (bool)root["volume"];
  if (s.has_volume) s.volume = p.volume(p.require(root, "", "volume"));
  if (is_mesh) s.mesh = p.mesh(root["mesh"], s.has_volume);
  // Left out: the default colour map over the data's range, as ParaView shows a new volume.
  if (root["transfer_function"]) s.tf = p.transferFunction(root["transfer_function"]);
  else if (!is_mesh) s.tf = transferFunctionPreset("cool-to-warm");
  if (root["light"]) {
    s.light = p.vec3(root["light"], "light");
    if (!(length(s.light) > 0)) p.fail("light", "must be non-zero (leave it out for a headlight)");
  }
  if (root["antialiasing"]) s.antialiasing = p.antialiasing(root["antialiasing"]);
  if (root["shading"] && is_mesh) p.fail("shading", "shades volume samples; a mesh is lit by `light` alone");
  if (root["shading"]) s.shading = p.shading(root["shading"]);
  // Left out: fitted to the volume's box (a mesh is fitted to the unit box).
  s.camera = root["camera"] ? p.camera(root["camera"]) : fittedCamera(sceneHalfExtent(s));
  if (root["image"]) {
    YAML::Node im = root["image"];
    if (!im.IsSequence() || im.size() != 2) p.fail("image", "expected [width, height], got " + Parser::describe(im));
    s.width = (int)p.integer(im[0], "image[0]", 1, 16384);
    s.height = (int)p.integer(im[1], "image[1]", 1, 16384);
    if (std::string m = imageSizeProblem(s.width, s.height); !m.empty()) p.fail("image", m);
  }
  if (root["quality"]) s.quality = p.quality(root["quality"]);
  if (root["orbit"]) s.orbit = p.orbit(root["orbit"]);
  return s;
}

}  // namespace tessera
