// Scene file parser (scenes/README.md): strict YAML with errors naming file and key path.
#include "common/scene.h"

#include <fmt/format.h>

#include <tuple>

#include "common/scene_parser.h"

namespace tessera {

Camera Orbit::at(const Camera& base, int frame) const {
  if (frames <= 1 || degrees == 0) return base;
  return base.orbited(axis, degrees * frame / frames);
}

namespace detail {

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
  checkKeys(n, "quality", {"step", "early_termination", "skip_empty", "jitter"});
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
  if (n["jitter"]) q.jitter = boolean(n["jitter"], "quality.jitter");
  return q;
}

Orbit Parser::orbit(const YAML::Node& n) const {
  checkKeys(n, "orbit", {"frames", "axis", "degrees"});
  Orbit o;
  if (n["frames"]) o.frames = (int)integer(n["frames"], "orbit.frames", 1, 1000000);
  if (n["degrees"]) o.degrees = number(n["degrees"], "orbit.degrees");
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

Crop Parser::crop(const YAML::Node& n) const {
  if (!n.IsMap()) fail("crop", "expected a map such as {x: [0, 0.5]}, got " + describe(n));
  checkKeys(n, "crop", {"x", "y", "z"});
  Crop c;
  for (int a = 0; a < 3; ++a) {
    const std::string key(1, "xyz"[a]), path = "crop." + key;
    if (!n[key]) continue;
    const YAML::Node v = n[key];
    if (!v.IsSequence() || v.size() != 2) fail(path, "expected [lo, hi], fractions of the box, got " + describe(v));
    const double lo = number(v[0], path + "[0]"), hi = number(v[1], path + "[1]");
    if (!(lo >= 0 && hi <= 1 && lo < hi))
      fail(path, fmt::format("[{}, {}]: expected 0 <= lo < hi <= 1 (fractions of the box)", lo, hi));
    c.axes[a] = {lo, hi};
  }
  return c;
}

ValueWindow Parser::window(const YAML::Node& n) const {
  if (!n.IsMap() || !n["level"] || !n["width"])
    fail("window", "expected {level: L, width: W} in the volume's values, got " + describe(n));
  checkKeys(n, "window", {"level", "width"});
  const ValueWindow w{number(n["level"], "window.level"), number(n["width"], "window.width")};
  if (!(w.width > 0)) fail("window.width", fmt::format("{}: expected a positive width of values", w.width));
  return w;
}

// A CT preset is in Hounsfield units: it sets the range. A DICOM CT series given neither a
// colour map nor a range gets ct-bone, and a note says so. Shading stays the scene's choice
// (it more than doubles a renderer's memory, and the OSMesa backend has none).
void ctPreset(const Parser& p, const YAML::Node& root, Scene& s) {
  const YAML::Node tf = root["transfer_function"];
  const std::string name = tf && tf.IsScalar() ? tf.Scalar() : "";
  auto* raw = s.has_volume && !s.mesh ? std::get_if<RawVolumeSpec>(&s.volume) : nullptr;
  const bool ct_default = raw && !tf && !raw->has_range && raw->modality == "CT";
  if (!isCtPreset(name) && !ct_default) return;
  if (!raw) p.fail("transfer_function", name + " is in Hounsfield units, for a CT file's volume");
  if (raw->has_range)
    p.fail("volume.range", "transfer_function " + name + " is in Hounsfield units over its own range (" +
                               std::to_string((int)kCtRange[0]) + ".." + std::to_string((int)kCtRange[1]) + "); leave range out");
  raw->has_range = true, raw->range = kCtRange;
  if (ct_default) {
    s.tf = transferFunctionPreset("ct-bone");
    raw->notes.push_back(std::string("a CT series with no transfer_function: shown with ct-bone (Hounsfield units") +
                         (s.blend == Blend::Composite ? "; `shading: true` lights it" : "") +
                         "); give transfer_function (ct-soft-tissue, or points over a range) to change it");
  }
}

}  // namespace detail

VoxelBox cropBox(const Crop& c, const std::array<int, 3>& dims) {
  VoxelBox b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = std::clamp((int)std::lround(c.axes[a][0] * dims[a]), 0, dims[a] - 1);
    b.hi[a] = std::clamp((int)std::lround(c.axes[a][1] * dims[a]), b.lo[a] + 1, dims[a]);
  }
  return b;
}

const char* blendName(Blend b) {
  switch (b) {
    case Blend::Maximum: return "maximum";
    case Blend::Minimum: return "minimum";
    case Blend::Composite: break;
  }
  return "composite";
}

Scene parseScene(const std::string& yaml_text, const std::string& base_dir, const std::string& name_for_errors) {
  detail::Parser p(name_for_errors, base_dir);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    p.fail("", "YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) p.fail("", "expected a map of scene keys at the top level");
  p.checkKeys(root, "",
              {"volume", "transfer_function", "camera", "image", "quality", "orbit", "mesh", "light", "antialiasing",
               "shading", "time", "blend", "crop", "window"});
  Scene s;
  s.path = name_for_errors;
  s.quality = namedQuality(QualityName::Default);
  // A mesh scene needs a volume only for its isosurface, and a transfer function not at all.
  const bool is_mesh = (bool)root["mesh"];
  s.has_volume = !is_mesh || (bool)root["volume"];
  if (s.has_volume) s.volume = p.volume(p.require(root, "", "volume"), s.series);
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
  if (root["blend"]) {
    if (is_mesh) p.fail("blend", "blends volume samples; a mesh scene has none");
    const std::string b = p.string(root["blend"], "blend");
    if (b == "maximum") s.blend = Blend::Maximum;
    else if (b == "minimum") s.blend = Blend::Minimum;
    else if (b != "composite")
      p.fail("blend", "'" + b + "': expected composite, maximum or minimum (maximum or minimum intensity projection)");
    if (isProjection(s.blend) && s.shading.on)
      p.fail("blend", b + " shows each ray's " + (s.blend == Blend::Maximum ? "largest" : "smallest") +
                          " value, which is not lit: leave `shading` out");
  }
  if (root["crop"]) {
    if (is_mesh) p.fail("crop", "cuts the rendered volume; a mesh scene renders none");
    s.crop = p.crop(root["crop"]);
  }
  if (root["window"]) {
    if (is_mesh) p.fail("window", "lays a volume's colour map over its values; a mesh scene has none");
    s.window = p.window(root["window"]);
  }
  detail::ctPreset(p, root, s);
  if (root["image"]) {
    YAML::Node im = root["image"];
    if (!im.IsSequence() || im.size() != 2) p.fail("image", "expected [width, height], got " + detail::Parser::describe(im));
    s.width = (int)p.integer(im[0], "image[0]", 1, 16384);
    s.height = (int)p.integer(im[1], "image[1]", 1, 16384);
    if (std::string m = imageSizeProblem(s.width, s.height); !m.empty()) p.fail("image", m);
  }
  // Left out: fitted to the volume's box (a mesh is fitted to the unit box) and the image.
  s.camera_fitted = !root["camera"];
  s.camera = root["camera"] ? p.camera(root["camera"])
                            : fittedCamera(s, (double)s.width / s.height);
  if (root["quality"]) s.quality = p.quality(root["quality"]);
  if (root["orbit"]) s.orbit = p.orbit(root["orbit"]);
  if (root["time"] && is_mesh) p.fail("time", "plays a volume's time steps; a mesh scene has none");
  if (root["time"]) s.time = p.playback(root["time"], s.series.steps);
  // Played without an orbit: one pass over the steps, the camera still.
  if (s.time.play && !root["orbit"]) s.orbit = Orbit{s.time.onePass(s.series.steps), {0, 1, 0}, 0};
  return s;
}

}  // namespace tessera
