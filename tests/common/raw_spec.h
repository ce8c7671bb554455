// A raw file's spec as a scene would give it (the header fields keep their defaults).
#pragma once
#include <string>

#include "common/volume.h"

namespace tessera::test {

inline RawVolumeSpec rawSpec(const std::string& file, std::array<int, 3> dims, VoxelType type,
                             std::array<double, 3> spacing, bool has_range, std::array<double, 2> range) {
  RawVolumeSpec s;
  s.file = file;
  s.dims = dims;
  s.type = type;
  s.spacing = spacing;
  s.has_range = has_range;
  s.range = range;
  return s;
}

}  // namespace tessera::test
