// The samples every volume-file test writes in some format, and the raw file of the same
// samples each format must load as (volume_files_test.cpp, volume_file_names_test.cpp).
#pragma once
#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "common/scene.h"
#include "tests/common/raw_spec.h"
#include "tests/common/temp_dir.h"

namespace tessera::test::files {

constexpr int kNx = 13, kNy = 11, kNz = 7;
const std::array<double, 3> kSpacing{0.75, 1.25, 2.5};

// Signed samples with a different value at every voxel, so any axis mix-up shows.
inline std::vector<int16_t> samples() {
  std::vector<int16_t> v((size_t)kNx * kNy * kNz);
  for (int z = 0; z < kNz; ++z)
    for (int y = 0; y < kNy; ++y)
      for (int x = 0; x < kNx; ++x) v[x + kNx * (y + kNy * z)] = (int16_t)(x * 3 - y * 40 + z * 500 - 900);
  return v;
}

inline Volume fromScene(const std::string& yaml, const std::string& dir, const VoxelBox* box = nullptr) {
  const Scene s = parseScene(yaml, dir, "s.yaml");
  return box ? loadVolume(s, *box) : loadVolume(s);
}

// The same samples as a raw int16 file: the reference every format must reproduce.
inline Volume rawReference(const TempDir& t) {
  const auto v = samples();
  const auto spec = test::rawSpec(t.write("ref.raw", v.data(), v.size() * 2), {kNx, kNy, kNz}, VoxelType::Int16,
                                  kSpacing, false, {0, 0});
  return loadRawVolume(spec);
}

inline void expectSameVolume(const Volume& a, const Volume& ref) {
  EXPECT_EQ(a.dims, ref.dims);
  EXPECT_EQ(a.spacing, ref.spacing);
  EXPECT_EQ(a.data_range, ref.data_range);
  EXPECT_EQ(a.values, ref.values);
}

inline void writeNifti(const std::string& path, double slope = 0, double inter = 0) {
  const int64_t dims[8] = {3, kNx, kNy, kNz, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
  ASSERT_NE(nim, nullptr);
  nim->dx = nim->pixdim[1] = kSpacing[0];
  nim->dy = nim->pixdim[2] = kSpacing[1];
  nim->dz = nim->pixdim[3] = kSpacing[2];
  nim->scl_slope = slope;
  nim->scl_inter = inter;
  const auto v = samples();
  std::memcpy(nim->data, v.data(), v.size() * 2);
  ASSERT_EQ(nifti_set_filenames(nim, path.c_str(), 0, 1), 0);
  nifti_image_write(nim);
  nifti_image_free(nim);
}

}  // namespace tessera::test::files
