// Scenes from files, the built-in default scene, and a scene's volume read or generated.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/io/volume_files.h"
#include "common/scene.h"

namespace tessera {

Scene loadScene(const std::string& path) {
  // A volume file whose header says what it holds (NIfTI, NRRD, DICOM, TIFF, or a folder of DICOM or TIFF slices) is the
  // scene `volume: {file: F}`: every default, from the data.
  if (volumeFormatOf(path) != VolumeFormat::Raw) {
    std::filesystem::path abs = std::filesystem::absolute(path).lexically_normal();
    if (!abs.has_filename()) abs = abs.parent_path();  // a folder given as "ct/"
    // Single-quoted YAML takes any bytes of a name ('' for '), also those that are not UTF-8.
    std::string name = abs.filename().string();
    for (size_t at = name.find('\''); at != std::string::npos; at = name.find('\'', at + 2)) name.insert(at, 1, '\'');
    Scene s = parseScene("volume: {file: '" + name + "'}\n", abs.parent_path().string(), path);
    s.path = path;
    // The built-in scene's orbit, so that a farm shown a file alone turns it the same way,
    // about the data's up (a 4-D file stays still: `time: {play: true}` plays its steps).
    if (s.series.steps <= 1) s.orbit = Orbit{defaultScene().orbit.frames, sceneView(s).up};
    return s;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  std::filesystem::path base = std::filesystem::path(path).parent_path();
  Scene s;
  try {
    s = parseScene(ss.str(), base.empty() ? "." : base.string(), path);
  } catch (const SceneError&) {
    // A raw volume given alone: its bytes are no scene (a UTF-16 scene, NULs and all, parses).
    if (ss.str().find('\0') == std::string::npos) throw;
    throw SceneError(path + ": not a scene file but binary data; a raw volume has no header to say its size and type, "
                            "so give them in a scene file: volume: {file: " +
                     std::filesystem::path(path).filename().string() + ", dims: [x, y, z], type: uint16}");
  }
  s.path = path;
  return s;
}

std::array<double, 2> mappedRange(const Scene& s) {
  const auto* raw = s.has_volume && !s.mesh ? std::get_if<RawVolumeSpec>(&s.volume) : nullptr;
  return raw && raw->has_range ? raw->range : std::array<double, 2>{0, 1};
}

ColorWindow colorWindow(const Scene& s, const std::array<double, 2>& range) {
  if (!s.window) return {};
  // A constant volume's value c is mapped as the master maps it, with c .. c + 1.
  const double span = range[1] > range[0] ? range[1] - range[0] : 1;
  ColorWindow w{(s.window->level - range[0]) / span, std::max(s.window->width / span, 1e-300)};
  // Held within what a frame may carry (ColorWindow::kLimit). Wider, the values 0..1 all sit
  // at one place of the map: kept there. Farther out at most kLimit wide, they sit beyond an
  // end of the map, as they do at kLimit.
  constexpr double kLimit = ColorWindow::kLimit;
  if (w.width > kLimit) {
    const double at = std::clamp(0.5 - w.center / w.width, -0.5, 1.5);  // where 0 lies on the map
    w = {(0.5 - at) * kLimit, kLimit};
  }
  w.center = std::clamp(w.center, -kLimit, kLimit);
  return w;
}

ColorWindow colorWindow(const Scene& s) { return colorWindow(s, mappedRange(s)); }

Vec3 sceneHalfExtent(const Scene& s) {
  if (!s.has_volume || s.mesh) return {0.5, 0.5, 0.5};
  Volume shape;
  shape.dims = volumeDims(s);
  const auto* raw = std::get_if<RawVolumeSpec>(&s.volume);
  shape.spacing = raw ? raw->spacing : std::get<GeneratorSpec>(s.volume).spacing;
  return shape.halfExtent();
}

SceneView sceneView(const Scene& s) {
  const auto* raw = s.has_volume && !s.mesh ? std::get_if<RawVolumeSpec>(&s.volume) : nullptr;
  const bool images = raw && (raw->format == VolumeFormat::Tiff || raw->format == VolumeFormat::Dicom);
  // A patient seen from the front needs a volume: one slice (a localizer) is seen as an image.
  if (images && raw->format == VolumeFormat::Dicom && raw->dims[2] > 1 && length(raw->anterior) > 0.5 &&
      length(raw->superior) > 0.5)
    return {raw->anterior, raw->superior};
  if (images) return {{0, 0, -1}, {0, -1, 0}};
  return {{0, 0, 1}, {0, 1, 0}};
}

Camera fittedCamera(const Scene& s, double aspect) {
  const SceneView v = sceneView(s);
  const Vec3 half = sceneHalfExtent(s);
  if (s.crop.whole() || !s.has_volume || s.mesh) return fittedCamera(half, aspect, v.front, v.up);
  // A crop is what is seen: its box (voxel i covers [i, i + 1) / dims of the volume's box),
  // framed as the volume's would be, from its centre.
  const auto dims = volumeDims(s);
  const VoxelBox b = cropBox(s.crop, dims);
  Vec3 lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = half[a] * (2.0 * b.lo[a] / dims[a] - 1);
    hi[a] = half[a] * (2.0 * b.hi[a] / dims[a] - 1);
  }
  Camera c = fittedCamera((hi - lo) * 0.5, aspect, v.front, v.up);
  const Vec3 centre = (lo + hi) * 0.5;
  c.eye = c.eye + centre;
  c.target = centre;
  return c;
}

Scene defaultScene() {
  Scene s;
  s.path = "";
  s.volume = GeneratorSpec{"hollow-shell", 256, 1, {1, 1, 1}};
  // Shell values peak at 0.5 (semi-transparent orange), the core at 1.0 (bright, nearly opaque).
  s.tf = TransferFunction({{0.00, 0.0, 0.0, 0.0, 0.0},
                           {0.05, 1.0, 0.45, 0.1, 0.0},
                           {0.50, 1.0, 0.55, 0.15, 0.06},
                           {0.70, 1.0, 0.8, 0.5, 0.2},
                           {1.00, 1.0, 1.0, 0.9, 0.9}});
  s.camera = Camera{{0, 0.6, 2.2}, {0, 0, 0}, {0, 1, 0}, 30, false, 1};
  s.width = 1024;
  s.height = 1024;
  s.quality = namedQuality(QualityName::Default);
  s.orbit = Orbit{90, {0, 1, 0}};
  return s;
}

Volume loadVolume(const Scene& scene) { return loadVolume(scene, VoxelBox{{0, 0, 0}, volumeDims(scene)}); }

std::array<int, 3> volumeDims(const Scene& scene) {
  if (const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume)) return raw->dims;
  const int n = std::get<GeneratorSpec>(scene.volume).size;
  return {n, n, n};
}

Volume loadVolume(const Scene& scene, const VoxelBox& box, int step, std::vector<float> storage) {
  return VolumeReader(scene).read(box, step, std::move(storage));
}

VolumeReader::VolumeReader(const Scene& scene) : scene_(scene) {}
VolumeReader::~VolumeReader() = default;

// A step in the file already open (a 4-D file's, or the one volume's) is read through it,
// further on by its offset; another file is opened in its place.
Volume VolumeReader::read(const VoxelBox& box, int step, std::vector<float> storage) {
  try {
    const auto spec = stepVolume(scene_, step);
    const auto* raw = std::get_if<RawVolumeSpec>(&spec);
    if (!raw) return generateVolume(std::get<GeneratorSpec>(spec), box);
    // The same samples file read the same way (a 4-D file's steps; NRRD headers of a series
    // may share one data file and differ in encoding): only the offset moves.
    const RawVolumeSpec& o = opened_;
    const bool same = raw_ && raw->samples() == o.samples() && raw->offset >= o.offset && raw->type == o.type &&
                      raw->big_endian == o.big_endian && raw->gzip == o.gzip && raw->gzip_start == o.gzip_start &&
                      raw->slope == o.slope && raw->inter == o.inter && raw->dims == o.dims &&
                      raw->has_range == o.has_range && raw->range == o.range;
    if (!same) {
      raw_.reset();  // closed before the next opens
      raw_.emplace(*raw);
      opened_ = *raw;
    }
    return raw_->read(box, std::move(storage), raw->offset - opened_.offset);
  } catch (const SceneError&) {
    raw_.reset();  // a stream that failed (corrupt data) is opened afresh by the next read
    throw;
  } catch (const std::exception& e) {
    raw_.reset();
    throw SceneError((scene_.path.empty() ? "<default scene>" : scene_.path) + ": volume: " + e.what());
  }
}

}  // namespace tessera
