// Scalar volumes: values normalised to [0,1] over the declared range, v[x + nx*(y + ny*z)].
// The volume fills the origin-centred box with extents proportional to dims x spacing,
// scaled so the largest extent is 1; voxel i sits at the centre of its cell.
// A window holds only a box of a bigger volume (a renderer's bricks and their ghost
// voxels): its values are the box's, `origin` is where the box starts in the whole
// volume and `whole_dims` the whole volume's dims, which alone set the world box.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/vec.h"

namespace tessera {

struct Volume {
  std::array<int, 3> dims{0, 0, 0};            // of the values held
  std::array<int, 3> origin{0, 0, 0};          // voxel index of values[0] in the whole volume
  std::array<int, 3> whole_dims{0, 0, 0};      // of the whole volume; {0,0,0}: the same as dims
  std::array<double, 3> spacing{1, 1, 1};
  std::vector<float> values;  // normalised, size dims[0]*dims[1]*dims[2]
  // In the file's units: the smallest and largest value of the data, and the range that
  // was mapped to 0..1 (the scene's `range`, else the data's own).
  std::array<double, 2> data_range{0, 1}, mapped_range{0, 1};
  // RawVolumeReader::readValues only: the values hold value - value_offset (in the file's units).
  double value_offset = 0;

  size_t index(int x, int y, int z) const { return x + (size_t)dims[0] * (y + (size_t)dims[1] * z); }
  float at(int x, int y, int z) const { return values[index(x, y, z)]; }
  size_t voxelCount() const { return (size_t)dims[0] * dims[1] * dims[2]; }
  std::array<int, 3> wholeDims() const { return whole_dims[0] > 0 ? whole_dims : dims; }
  bool isWindow() const { return wholeDims() != dims; }
  // Half extents of the whole volume's box in world units (largest is 0.5).
  Vec3 halfExtent() const;
  Vec3 boxMin() const { return halfExtent() * -1.0; }
  Vec3 boxMax() const { return halfExtent(); }
};

enum class VoxelType { UInt8, UInt16, Float32, Int8, Int16, Int32, UInt32, Float64 };
// "uint8", "int16", ...; and back (nullopt for an unknown word).
const char* voxelTypeName(VoxelType t);
std::optional<VoxelType> voxelTypeFromName(const std::string& name);

// Where a volume's samples are. A raw file has no header: the scene gives dims and type.
// NIfTI and NRRD files give them (and spacing, byte order, offset, compression) in their
// header, read by the scene parser (common/io/volume_files.h); the reader is the same.
enum class VolumeFormat { Raw, Nifti, Nrrd, Dicom, Tiff };

// One slice of a volume kept slice by slice. A DICOM series' slice: its file, where its
// samples start in it (uncompressed), or that GDCM must decode it (a compressed transfer
// syntax), and its scaling (a slice's own: PET and MR series may scale each slice
// differently). A TIFF stack's: its file and its page (offset: the image file directory).
struct SliceFile {
  std::string file;
  uint64_t offset = 0;
  bool encoded = false;
  double slope = 1, inter = 0;
  int bits_stored = 0;  // the sample's bits, at the bottom of its type's (0: all of them)
  bool bottom_up = false;  // a TIFF page stored bottom row first
};

struct RawVolumeSpec {
  std::string file;  // absolute or relative to the scene's folder (resolved by the parser)
  std::array<int, 3> dims{0, 0, 0};
  VoxelType type = VoxelType::UInt8;
  std::array<double, 3> spacing{1, 1, 1};
  bool spacing_given = false;           // by the scene (volume.spacing), over a header's
  bool has_range = false;               // else the data's own min..max is mapped to 0..1
  std::array<double, 2> range{0, 255};
  VolumeFormat format = VolumeFormat::Raw;
  std::string data_file;                // the samples' file when not `file` (NRRD "data file")
  uint64_t offset = 0;                  // bytes before the first sample (of the gzip stream's content)
  bool big_endian = false, gzip = false;
  uint64_t gzip_start = 0;              // file byte where the gzip stream starts (after an attached header)
  double slope = 1, inter = 0;          // value = slope * stored + inter (NIfTI scl_slope, scl_inter)
  bool read_once = false;               // a series' step: what is not in the page cache bypasses it
  std::vector<SliceFile> slices;        // a DICOM series (k along the slices' normal) or a TIFF stack: slice k
  double dicom_tilt_degrees = 0;        // how far its slices shift in their plane (a gantry tilt): drawn unsheared, a note says so
  Vec3 anterior{0, 0, 0}, superior{0, 0, 0};  // a DICOM series: those patient directions along x, y, z (else 0)
  std::string modality;                 // a DICOM series' Modality (CT: values in Hounsfield units)
  std::vector<std::string> notes;       // what the header left to a guess (an ImageJ stack's axes): warnings
  std::array<bool, 3> spacing_known{true, true, true};  // false: the file lacks that axis's spacing (1; a warning)
  const std::string& samples() const { return data_file.empty() ? file : data_file; }
};

struct GeneratorSpec {
  std::string name;  // one of generatorNames()
  int size = 64;     // cube edge in voxels
  uint32_t seed = 1;
  std::array<double, 3> spacing{1, 1, 1};
  // A time-varying generator (isTimeGenerator): where in its period, in [0, 1), the volume is.
  double time = 0;
};

// Checks done where a scene is read and again before loading; each returns "" when fine,
// else what is wrong (the caller adds the file and key).
// Spacing: finite, in [kMinSpacing, kMaxSpacing], largest / smallest <= kMaxSpacingRatio.
inline constexpr double kMinSpacing = 1e-30, kMaxSpacing = 1e30, kMaxSpacingRatio = 1e6;
std::string spacingProblem(const std::array<double, 3>& spacing);
// "" for a regular file, else e.g. "is a directory", "is a FIFO (named pipe), not a regular file", "file not found".
std::string notRegularFile(const std::string& path);
// Bytes needed to hold a volume of dims as normalised floats (files are read in pieces).
uint64_t volumeLoadBytes(const std::array<int, 3>& dims);
uint64_t physicalMemoryBytes();
// "" if volumeLoadBytes fits in this machine's physical memory, else a sentence with both sizes.
std::string memoryProblem(const std::array<int, 3>& dims);
size_t voxelTypeSize(VoxelType t);

// A box of voxels [lo, hi) of a volume.
struct VoxelBox {
  std::array<int, 3> lo{0, 0, 0}, hi{0, 0, 0};
  // Element by element: the defaulted one called memcmp, 1.6% of a farm's renderer time
  // (boxes are compared per ray).
  bool operator==(const VoxelBox& o) const {
    return lo[0] == o.lo[0] && lo[1] == o.lo[1] && lo[2] == o.lo[2] && hi[0] == o.hi[0] && hi[1] == o.hi[1] &&
           hi[2] == o.hi[2];
  }
};

// Throws std::runtime_error naming the file: missing file, size != dims x type size,
// non-finite value (with the first offending index).
Volume loadRawVolume(const RawVolumeSpec& spec);
// Only the voxels of `box` (a window), read with positioned reads; memory grows with the
// box, not the file. With no `range`, the data's min..max is found by streaming the whole
// file once in slabs (the normalisation must be the whole volume's); non-finite values
// anywhere in the file are refused as loadRawVolume refuses them.
// `storage`: memory to read into (a freed window of the same size: no page faults, no zeroing).
Volume loadRawVolume(const RawVolumeSpec& spec, const VoxelBox& box, std::vector<float> storage = {});
// Bytes of samples this process read from volume files (decompressed bytes for a gzip
// stream): a renderer says at exit that it read its bricks, not the file.
uint64_t volumeSamplesRead();
// A file's sample normalised with the range lo..hi as every read normalises it: in double,
// clamped to 0..1; lo == hi maps everything to 0.
inline float normaliseSample(float x, double lo, double hi) {
  const double scale = hi > lo ? 1.0 / (hi - lo) : 0.0;
  return (float)std::clamp((x - lo) * scale, 0.0, 1.0);
}
// Bytes zlib decompressed for gzip files, the bytes a read skips included: a gzip stream
// read forwards once costs its samples once; one reopened for every window costs far more.
// With them, what DICOM's compressed slices and TIFF strips decoded to (whole slices, whole
// strips: rows no window asked for included).
uint64_t volumeBytesInflated();
// The same file opened once for many windows, as loadRawVolume reads them. Windows read in
// file order (slabs of planes front to back) cost one pass over the file in all: a gzip
// stream is decoded once, not from its start for every window. With no declared range the
// first window scans the whole file first (one more pass; fixVolumeRange does it once for
// the scene instead), and later windows reuse that scan.
class RawVolumeReader {
 public:
  explicit RawVolumeReader(RawVolumeSpec spec);  // throws as loadRawVolume does
  ~RawVolumeReader();
  // `shift`: bytes past the spec's offset where the window's volume starts (a 4-D file's
  // step t lies t steps of samples further on).
  Volume read(const VoxelBox& box, std::vector<float> storage = {}, uint64_t shift = 0);
  // The window's samples as the file holds them (after a header's scaling; non-finite ones
  // refused), not normalised, less value_offset (a value near the data's, so that float32 keeps
  // their differences): data_range and mapped_range are their min..max in the file's units. With no scan
  // first, slabs read this way give a file's range and its blocks' in one pass (the master's
  // summary: normalising is monotonic, so a block's normalised bounds are its bounds normalised).
  Volume readValues(const VoxelBox& box);

 private:
  Volume read(const VoxelBox& box, std::vector<float> storage, uint64_t shift, bool map);
  struct Open;
  std::unique_ptr<Open> open_;
};
// Throws std::invalid_argument for an unknown name or size < 2. A box gives a window:
// each voxel is computed from its position in the whole volume, so windows equal the
// matching part of the whole.
// The generators' names as messages list them ("hollow-shell | marschner-lobb | ..."), and
// whether `name` is one of them.
const std::string& generatorNames();
bool isGeneratorName(const std::string& name);
// Generators whose volume changes with GeneratorSpec::time (a scene gives them `steps`).
bool isTimeGenerator(const std::string& name);
Volume generateVolume(const GeneratorSpec& spec);
Volume generateVolume(const GeneratorSpec& spec, const VoxelBox& box);
// "" if box is a non-empty box inside a volume of `whole` dims, else what is wrong.
std::string windowProblem(const std::array<int, 3>& whole, const VoxelBox& box);
// "" if the mapped range meets the data's values, else a sentence saying that every voxel
// maps to one end of the transfer function and what to do.
std::string rangeProblem(const Volume& v);

}  // namespace tessera
