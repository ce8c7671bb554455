// Scalar volumes: values normalised to [0,1] over the declared range, v[x + nx*(y + ny*z)].
// The volume fills the origin-centred box with extents proportional to dims x spacing,
// scaled so the largest extent is 1; voxel i sits at the centre of its cell.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/vec.h"

namespace tessera {

struct Volume {
  std::array<int, 3> dims{0, 0, 0};
  std::array<double, 3> spacing{1, 1, 1};
  std::vector<float> values;  // normalised, size dims[0]*dims[1]*dims[2]
  // In the file's units: the smallest and largest value of the data, and the range that
  // was mapped to 0..1 (the scene's `range`, else the data's own).
  std::array<double, 2> data_range{0, 1}, mapped_range{0, 1};

  size_t index(int x, int y, int z) const { return x + (size_t)dims[0] * (y + (size_t)dims[1] * z); }
  float at(int x, int y, int z) const { return values[index(x, y, z)]; }
  size_t voxelCount() const { return (size_t)dims[0] * dims[1] * dims[2]; }
  // Half extents of the box in world units (largest is 0.5).
  Vec3 halfExtent() const;
  Vec3 boxMin() const { return halfExtent() * -1.0; }
  Vec3 boxMax() const { return halfExtent(); }
};

enum class VoxelType { UInt8, UInt16, Float32 };

struct RawVolumeSpec {
  std::string file;  // absolute or relative to the scene's folder (resolved by the parser)
  std::array<int, 3> dims{0, 0, 0};
  VoxelType type = VoxelType::UInt8;
  std::array<double, 3> spacing{1, 1, 1};
  bool has_range = false;               // else the data's own min..max is mapped to 0..1
  std::array<double, 2> range{0, 255};
};

struct GeneratorSpec {
  std::string name;  // hollow-shell | marschner-lobb | noise-cloud
  int size = 64;     // cube edge in voxels
  uint32_t seed = 1;
  std::array<double, 3> spacing{1, 1, 1};
};

// Checks done where a scene is read and again before loading; each returns "" when fine,
// else what is wrong (the caller adds the file and key).
// Spacing: finite, in [kMinSpacing, kMaxSpacing], largest / smallest <= kMaxSpacingRatio.
inline constexpr double kMinSpacing = 1e-30, kMaxSpacing = 1e30, kMaxSpacingRatio = 1e6;
std::string spacingProblem(const std::array<double, 3>& spacing);
// "" for a regular file, else e.g. "is a directory", "is a FIFO (named pipe), not a regular file", "file not found".
std::string notRegularFile(const std::string& path);
// Bytes needed to load a volume: the normalised floats plus the file read whole (0 for generators).
uint64_t volumeLoadBytes(const std::array<int, 3>& dims, size_t file_bytes_per_voxel);
uint64_t physicalMemoryBytes();
// "" if volumeLoadBytes fits in this machine's physical memory, else a sentence with both sizes.
std::string memoryProblem(const std::array<int, 3>& dims, size_t file_bytes_per_voxel);
size_t voxelTypeSize(VoxelType t);

// Throws std::runtime_error naming the file: missing file, size != dims x type size,
// non-finite value (with the first offending index).
Volume loadRawVolume(const RawVolumeSpec& spec);
// Throws std::invalid_argument for an unknown name or size < 2.
Volume generateVolume(const GeneratorSpec& spec);
// "" if the mapped range meets the data's values, else a sentence saying that every voxel
// maps to one end of the transfer function and what to do.
std::string rangeProblem(const Volume& v);

}  // namespace tessera
