// The scene as YAML with every default filled in (what `tessera-info` prints, as `docker
// compose config` prints the effective file): parsing it again gives the same Scene.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <filesystem>

#include "common/scene.h"

namespace tessera {
namespace {

// The shortest text that parses back to the same double: 0.231, not 0.23100000000000001.
std::string num(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

void vec(YAML::Emitter& e, const Vec3& v) {
  e << YAML::Flow << YAML::BeginSeq << num(v.x) << num(v.y) << num(v.z) << YAML::EndSeq;
}

template <class T, size_t N>
void list(YAML::Emitter& e, const std::array<T, N>& a) {
  e << YAML::Flow << YAML::BeginSeq;
  for (const T& x : a) {
    if constexpr (std::is_floating_point_v<T>) e << num(x);
    else e << x;
  }
  e << YAML::EndSeq;
}

// Absolute: the printed scene is saved anywhere (a path relative to the folder it was read
// from named another file once saved beside it).
std::string absolutePath(const std::string& p) { return std::filesystem::absolute(p).lexically_normal().string(); }

void volume(YAML::Emitter& e, const Scene& s) {
  e << YAML::Key << "volume" << YAML::Value << YAML::BeginMap;
  if (const auto* raw = std::get_if<RawVolumeSpec>(&s.volume)) {
    if (s.series.files.empty()) {
      e << YAML::Key << "file" << YAML::Value << absolutePath(raw->file);
    } else if (!s.series.pattern.empty()) {
      e << YAML::Key << "series" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "pattern" << YAML::Value
        << s.series.pattern << YAML::Key << "first" << YAML::Value << s.series.first << YAML::Key << "last"
        << YAML::Value << s.series.first + s.series.steps - 1 << YAML::EndMap;
    } else {  // as a list: a .series file lists the same names
      e << YAML::Key << "series" << YAML::Value << YAML::BeginSeq;
      for (const auto& f : s.series.files) e << absolutePath(f);
      e << YAML::EndSeq;
    }
    if (raw->format == VolumeFormat::Raw) {  // a NIfTI or NRRD header gives them
      e << YAML::Key << "dims" << YAML::Value;
      list(e, raw->dims);
      e << YAML::Key << "type" << YAML::Value << voxelTypeName(raw->type);
    }
    if (raw->format == VolumeFormat::Raw || raw->spacing_given) {  // else the header's, as dims
      e << YAML::Key << "spacing" << YAML::Value;
      list(e, raw->spacing);
    }
    if (raw->has_range) {  // left out, the data's own min..max is mapped
      e << YAML::Key << "range" << YAML::Value;
      list(e, raw->range);
    }
  } else {
    const auto& g = std::get<GeneratorSpec>(s.volume);
    e << YAML::Key << "generator" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "name"
      << YAML::Value << g.name << YAML::Key << "size" << YAML::Value << g.size << YAML::Key << "seed" << YAML::Value
      << g.seed;
    if (s.series.steps > 1) e << YAML::Key << "steps" << YAML::Value << s.series.steps;
    e << YAML::EndMap;
    e << YAML::Key << "spacing" << YAML::Value;
    list(e, g.spacing);
  }
  e << YAML::EndMap;
}

void camera(YAML::Emitter& e, const Camera& c) {
  e << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "eye" << YAML::Value;
  vec(e, c.eye);
  e << YAML::Key << "target" << YAML::Value;
  vec(e, c.target);
  e << YAML::Key << "up" << YAML::Value;
  vec(e, c.up);
  if (c.orthographic) e << YAML::Key << "orthographic" << YAML::Value << true << YAML::Key << "height" << YAML::Value << num(c.height);
  else e << YAML::Key << "fov" << YAML::Value << num(c.fov);
  e << YAML::EndMap;
}

void quality(YAML::Emitter& e, const Quality& q) {
  e << YAML::Key << "quality" << YAML::Value;
  if (q.name != QualityName::Custom) {
    e << qualityName(q.name);
    return;
  }
  e << YAML::BeginMap << YAML::Key << "step" << YAML::Value << num(q.step) << YAML::Key << "early_termination"
    << YAML::Value << num(q.early_termination) << YAML::Key << "skip_empty" << YAML::Value << q.skip_empty
    << YAML::Key << "jitter" << YAML::Value << q.jitter << YAML::EndMap;
}

}  // namespace

std::string sceneYaml(const Scene& s) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  if (s.has_volume) volume(e, s);
  if (s.mesh) {
    e << YAML::Key << "mesh" << YAML::Value;
    if (!s.mesh->file.empty()) e << s.mesh->file;
    else
      e << YAML::BeginMap << YAML::Key << "isosurface" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "of" << YAML::Value << "volume" << YAML::Key << "level" << YAML::Value << num(s.mesh->level) << YAML::EndMap
        << YAML::EndMap;
  }
  if (!s.tf.points().empty()) {
    e << YAML::Key << "transfer_function" << YAML::Value << YAML::BeginSeq;
    for (const TfPoint& p : s.tf.points())
      e << YAML::Flow << YAML::BeginSeq << num(p.s) << num(p.r) << num(p.g) << num(p.b) << num(p.a) << YAML::EndSeq;
    e << YAML::EndSeq;
  }
  camera(e, s.camera);
  e << YAML::Key << "image" << YAML::Value << YAML::Flow << YAML::BeginSeq << s.width << s.height << YAML::EndSeq;
  quality(e, s.quality);
  e << YAML::Key << "orbit" << YAML::Value << YAML::BeginMap << YAML::Key << "frames" << YAML::Value << s.orbit.frames
    << YAML::Key << "axis" << YAML::Value;
  vec(e, s.orbit.axis);
  e << YAML::Key << "degrees" << YAML::Value << num(s.orbit.degrees);
  e << YAML::EndMap;
  const Playback& t = s.time;
  if (t != Playback{})
    e << YAML::Key << "time" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "play" << YAML::Value
      << t.play << YAML::Key << "stride" << YAML::Value << t.stride << YAML::Key << "mode" << YAML::Value
      << playbackModeName(t.mode) << YAML::Key << "step" << YAML::Value << t.step << YAML::EndMap;
  if (length(s.light) > 0) {
    e << YAML::Key << "light" << YAML::Value;
    vec(e, s.light);
  }
  if (s.shading.on)
    e << YAML::Key << "shading" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "ambient"
      << YAML::Value << num(s.shading.ambient) << YAML::Key << "diffuse" << YAML::Value << num(s.shading.diffuse)
      << YAML::Key << "specular" << YAML::Value << num(s.shading.specular) << YAML::Key << "shininess"
      << YAML::Value << num(s.shading.shininess) << YAML::EndMap;
  if (s.blend != Blend::Composite) e << YAML::Key << "blend" << YAML::Value << blendName(s.blend);
  if (!s.crop.whole()) {
    e << YAML::Key << "crop" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (int a = 0; a < 3; ++a)
      if (s.crop.axes[a] != Crop{}.axes[a]) {
        e << YAML::Key << std::string(1, "xyz"[a]) << YAML::Value;
        list(e, s.crop.axes[a]);
      }
    e << YAML::EndMap;
  }
  if (s.window)
    e << YAML::Key << "window" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "level" << YAML::Value
      << num(s.window->level) << YAML::Key << "width" << YAML::Value << num(s.window->width) << YAML::EndMap;
  if (s.mesh) {
    e << YAML::Key << "antialiasing" << YAML::Value << YAML::BeginMap << YAML::Key << "method" << YAML::Value
      << aaMethodName(s.antialiasing.method);
    if (s.antialiasing.method == AaMethod::Msaa || s.antialiasing.method == AaMethod::Ssaa)
      e << YAML::Key << "samples" << YAML::Value << s.antialiasing.samples;
    if (s.antialiasing.method == AaMethod::Fft) e << YAML::Key << "sigma" << YAML::Value << num(s.antialiasing.sigma);
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

namespace {

uint64_t fnv1a(std::string_view text, uint64_t h = 14695981039346656037ull) {
  for (const char c : text) h = (h ^ (unsigned char)c) * 1099511628211ull;
  return h;
}

// A Hello's scene is a protocol string (at most 64 KiB): a long series is listed by its ends,
// and any longer text (a colour map of thousands of points) is cut, with a hash of the whole.
constexpr size_t kListedSteps = 64, kMaxIdentity = 32 * 1024;

// "/name": a file by its name alone (a folder, such as a DICOM series', by its own name).
void byName(std::string& f) {
  std::filesystem::path p = std::filesystem::path(f).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  f = (std::filesystem::path("/") / p.filename()).string();
}

}  // namespace

std::string sceneIdentity(const Scene& scene) {
  Scene s = scene;
  // The master sends these with every frame; a stage's own are never used.
  s.camera = Camera{}, s.camera_fitted = false, s.quality = Quality{}, s.orbit = Orbit{}, s.time = Playback{};
  s.window.reset();
  // Each host keeps its files where it likes: a file is known by its name.
  auto* raw = std::get_if<RawVolumeSpec>(&s.volume);
  if (raw) byName(raw->file);
  for (std::string& f : s.series.files) byName(f);
  s.series.pattern.clear();  // its folder is this host's: the names, as a list's, are compared
  if (s.mesh && !s.mesh->file.empty()) byName(s.mesh->file);
  if (const size_t n = s.series.files.size(); n > kListedSteps) {
    uint64_t h = fnv1a("");
    for (const std::string& f : s.series.files) h = fnv1a(f + '\n', h);
    s.series.files = {s.series.files.front(), fmt::format("/... {} more, the names' hash {:016x} ...", n - 2, h),
                      s.series.files.back()};
  }
  std::string text = sceneYaml(s);
  // A file of another size or type under the same name: what its header says, which sceneYaml
  // leaves to the header.
  if (s.has_volume && raw && raw->format != VolumeFormat::Raw)
    text += fmt::format("header: {{dims: [{}, {}, {}], type: {}, spacing: [{}, {}, {}]}}\n", raw->dims[0],
                        raw->dims[1], raw->dims[2], voxelTypeName(raw->type), num(raw->spacing[0]),
                        num(raw->spacing[1]), num(raw->spacing[2]));
  if (text.size() > kMaxIdentity)
    text = text.substr(0, kMaxIdentity) + fmt::format("\n... the whole text's hash {:016x}\n", fnv1a(text));
  return text;
}

}  // namespace tessera
