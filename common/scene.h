// The scene file (scenes/README.md): one YAML file every process and tool takes.
// Unknown keys, missing keys and bad values are errors naming the key's path.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "common/camera.h"
#include "common/quality.h"
#include "common/transfer_function.h"
#include "common/volume.h"

namespace tessera {

// The run's frames: frame k's camera is the scene's turned by k*degrees/frames about axis.
// A time series played without an orbit runs one pass over its steps with degrees 0.
struct Orbit {
  int frames = 1;
  Vec3 axis{0, 1, 0};
  double degrees = 360;
  Camera at(const Camera& base, int frame) const;
};

// The volume's time steps (`volume: {series: ...}`, a 4-D file, or a time-varying generator
// with `steps`), all of one shape: the same dims and type, and the same spacing unless the
// scene's volume.spacing replaces the headers'. Opening a series reads
// the first step's header only; later steps are checked when first read (stepVolume).
struct TimeSeries {
  int steps = 1;
  std::vector<std::string> files;  // one file per step, resolved; empty: one file (or a generator)
  std::vector<double> times;       // each step's time (a .series file's), else empty: the index
  uint64_t step_bytes = 0;         // steps in one file: bytes from one step's samples to the next
  // A pattern series: its pattern, absolute ('%' of the folder doubled), and first number,
  // so the effective scene says it in three lines, not a line per step.
  std::string pattern;
  long long first = 0;
  bool operator==(const TimeSeries&) const = default;
};

// `time:` how a run plays the steps: frame k shows stepAt(k).
struct Playback {
  enum class Mode { Loop, Once, Swing };  // wrap around | stop on the last | back and forth
  bool play = false;                      // false: every frame shows `step`
  int stride = 1;                         // steps per frame; negative plays backwards
  Mode mode = Mode::Loop;
  int step = 0;                           // the first frame's
  int stepAt(uint64_t frame, int steps) const;
  int onePass(int steps) const;           // frames to show every step once (swing: there and back)
  bool operator==(const Playback&) const = default;
};
const char* playbackModeName(Playback::Mode m);

// `mesh:` (geometry scenes, drawn by the OSMesa backend): a .ply/.obj file (path resolved
// against the scene's folder; fitted to the unit box) or the isosurface of the scene's volume.
struct MeshSpec {
  std::string file;         // empty for an isosurface
  double level = 0.5;       // isosurface level, normalised scalar
  bool operator==(const MeshSpec&) const = default;
};
// `shading:` gradient lighting of volume samples, as VTK's and ParaView's "Shade": a sample's
// colour becomes min(1, colour * (ambient + diffuse * |N.L|) + specular * |N.H|^shininess)
// (a white light, lit from both sides), N the direction of the data's gradient, L towards the
// light (`light`, else a headlight at the eye) and H halfway between L and the eye. Opacity is
// unchanged. docs/DESIGN.md defines the gradient.
struct Shading {
  bool on = false;
  double ambient = 0.1, diffuse = 0.7, specular = 0.2, shininess = 10;  // VTK's defaults
  bool operator==(const Shading&) const = default;
};

// `blend:` how a ray's samples make its pixel, as VTK's and ParaView's blend modes: `composite`
// (front-to-back emission and absorption, the default), `maximum` (maximum intensity
// projection: the colour map at the largest value along the ray) or `minimum` (minimum
// intensity projection, at the smallest: airways and vessels darker than their surroundings);
// the two projections: common/max_intensity.h.
enum class Blend { Composite, Maximum, Minimum };
const char* blendName(Blend b);
inline bool isProjection(Blend b) { return b != Blend::Composite; }

// `crop: {x: [lo, hi], y: ..., z: ...}`: only this part of the volume is rendered, as
// ParaView's Crop and 3D Slicer's ROI cut a volume open; each axis a fraction of the box
// (0..1, lo < hi), an axis left out whole. Samples outside it count for nothing; inside, the
// data around the cut (trilinear neighbours, gradients) is the volume's own.
struct Crop {
  std::array<std::array<double, 2>, 3> axes{{{0, 1}, {0, 1}, {0, 1}}};
  bool whole() const { return axes == Crop{}.axes; }
  bool operator==(const Crop&) const = default;
};
// The crop in voxels of a volume of `dims`: each face at the nearest voxel boundary, at least
// one voxel wide.
VoxelBox cropBox(const Crop& c, const std::array<int, 3>& dims);

// `window: {level: L, width: W}`: the colour map laid over L - W/2 .. L + W/2 of the volume's
// values, in its own units (Hounsfield for a CT), as a CT viewer's window/level: what the
// window's right-drag sets, and the master says once a drag ends. Left out: over its range.
struct ValueWindow {
  double level = 0, width = 1;
  double lo() const { return level - width / 2; }
  double hi() const { return level + width / 2; }
  bool operator==(const ValueWindow&) const = default;
};

struct Scene {
  std::string path;  // file it was loaded from ("" for built-in)
  std::variant<RawVolumeSpec, GeneratorSpec> volume;
  bool has_volume = true;           // false for a mesh scene without `volume:`
  std::optional<MeshSpec> mesh;     // set: a geometry scene
  Vec3 light{0, 0, 0};              // world direction towards the light; zero: headlight
  Shading shading;                  // volumes only
  Blend blend = Blend::Composite;   // volumes only
  Crop crop;                        // volumes only
  std::optional<ValueWindow> window;  // volumes only
  Antialiasing antialiasing;
  TransferFunction tf;
  Camera camera;
  bool camera_fitted = false;  // no `camera` key: fitted to the box and the image (fittedCamera)
  int width = 512, height = 512;
  Quality quality;
  Orbit orbit;
  TimeSeries series;
  Playback time;
};

// Limits checked where a scene is read, so that no renderer meets them later. Each *Problem
// function returns "" when fine, else the value and the limit (the caller adds file and key).
inline constexpr double kMinStep = 0x1p-19;  // sqrt(3) / step < 2^20 samples on the longest ray
inline constexpr double kMaxStep = 0.25;     // >= 4 samples across the volume (it spans 1)
inline constexpr double kMinFov = 0.01, kMaxFov = 179;                       // degrees
inline constexpr double kMinCameraDistance = 1e-6, kMaxCameraDistance = 1e6;  // and |coordinate| <= max
inline constexpr double kMinOrthoHeight = 1e-6, kMaxOrthoHeight = 1e6;
// A piece may be the whole image in the widest pixel format (rgba32f, 16 bytes per pixel).
inline constexpr long long kMaxImagePixels = 16ll << 20;  // kMaxPayload (256 MiB) / 16
std::string stepProblem(double step);
std::string imageSizeProblem(int width, int height);
struct KeyProblem {
  std::string key, what;  // what == "": fine
};
KeyProblem cameraProblem(const Camera& c);

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Parses YAML text; relative paths resolve against base_dir. Throws SceneError whose
// message names the file and key path, e.g. "scene.yaml: camera.fov: expected a number".
Scene parseScene(const std::string& yaml_text, const std::string& base_dir,
                 const std::string& name_for_errors = "<scene>");
// A scene file, or a volume file that says what it holds (NIfTI, NRRD, TIFF, a DICOM series or
// its folder): then the scene `volume: {file: F}` with every default.
Scene loadScene(const std::string& path);
// The scene as YAML with every default filled in; parseScene of it gives the same Scene.
std::string sceneYaml(const Scene& s);
// What every stage of one farm must have read alike (stages read their own copy of the scene
// file, on their own hosts): sceneYaml less what the master sends with each frame (camera,
// quality, orbit, time playback, colour window), each file named by its name alone. The master refuses a
// stage whose identity differs from its own (Hello.scene).
std::string sceneIdentity(const Scene& s);
// The built-in default scene (a hollow shell) that runs with no file.
Scene defaultScene();
// "" when a farm of `renderers` (one brick each, or more) renders `q` within the accuracy
// contract (1/255 of tessera-render); else why not and what to change. Bricks terminate their
// rays separately: early termination at e can leave (1 - e) * 255 levels out of one process.
std::string farmAccuracyProblem(const Quality& q, int renderers);
// Loads or generates the scene's volume (of step 0 for a series).
Volume loadVolume(const Scene& scene);
// Only the voxels of `box` (a renderer's bricks and their ghost voxels) of time step `step`:
// see loadRawVolume and stepVolume.
// `storage`: memory a file's samples may be read into (see loadRawVolume).
Volume loadVolume(const Scene& scene, const VoxelBox& box, int step = 0, std::vector<float> storage = {});
// The scene's volume opened once for many windows (see RawVolumeReader): windows read in
// file order cost one pass over a compressed file (plus a scan when no range is declared:
// see fixVolumeRange), not one from its start each; a window before the last one read
// restarts the stream. Slabs front
// to back (the master's summary, isosurfaces, tessera-info's histogram) and the steps of a
// 4-D file played forwards are. `scene` must outlive the reader; one thread at a time.
// Throws as loadVolume does.
class VolumeReader {
 public:
  explicit VolumeReader(const Scene& scene);
  ~VolumeReader();
  Volume read(const VoxelBox& box, int step = 0, std::vector<float> storage = {});

 private:
  const Scene& scene_;
  std::optional<RawVolumeReader> raw_;  // of the file last read
  RawVolumeSpec opened_;                // what raw_ was opened with
};
// Where step `step` of the scene's volume is: its file (a series), its offset (a 4-D file)
// or its generator time. A step's own header is read and checked against step 0's: throws
// std::runtime_error naming the file, the field and both values when they differ (spacing
// only when the scene gives none), or the step when it is outside 0..steps-1. The scene's
// range and spacing apply to every step.
std::variant<RawVolumeSpec, GeneratorSpec> stepVolume(const Scene& scene, int step);
// The volume's dims from the scene alone (no voxel read).
std::array<int, 3> volumeDims(const Scene& scene);
// The values a volume scene's colour map spans: the file's `range` (fixed by the time a farm
// runs: the master's, see fixVolumeRange), or 0..1 (a generated volume, or a file whose range
// is not known yet).
std::array<double, 2> mappedRange(const Scene& s);
// The scene's `window` in fractions of `range` (the default window without one).
ColorWindow colorWindow(const Scene& s, const std::array<double, 2>& range);
ColorWindow colorWindow(const Scene& s);  // of mappedRange(s)

// Half extents of the scene's box from the volume's dims and spacing (no voxel read); a mesh
// scene's unit box.
Vec3 sceneHalfExtent(const Scene& s);
// Where a volume's front and up are, in the box: a DICOM series' anterior and superior (a
// patient seen from the front, head up, as a 3D viewer first shows one); a TIFF stack's (or
// a single DICOM slice's) slice 0 and row 0 (as Fiji shows a stack: rows going down, slice 0
// in front); else +z, +y.
struct SceneView {
  Vec3 front, up;
};
SceneView sceneView(const Scene& s);
// The camera a scene without `camera` gets for an image of this aspect: fittedCamera of its
// box (of its crop's box, when it has one, looking at its centre) from its sceneView.
Camera fittedCamera(const Scene& s, double aspect);

}  // namespace tessera
