// nifticlib says only "bad header" (on stderr) when it refuses a file; the error says what is
// wrong with the bytes (common/io/nifti_header.cpp).
#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <fmt/format.h>
#include <zlib.h>

#include "tests/common/load_error.h"
#include "tests/common/temp_dir.h"

namespace tessera {
namespace {

// The bytes of a 4 x 4 x 4 int16 .nii as nifticlib writes it (zeros), written to `path`.
std::string nifti4x4x4(const std::string& path) {
  const int64_t dims[8] = {3, 4, 4, 4, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
  if (!nim || nifti_set_filenames(nim, path.c_str(), 0, 1) != 0) return "";
  nifti_image_write(nim);
  nifti_image_free(nim);
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(NiftiHeader, ABadHeaderIsSaidByWhatIsWrong) {
  test::TempDir t("bad-nifti-bytes");
  const std::string good = nifti4x4x4(t.file("good.nii"));
  ASSERT_GT(good.size(), 352u);
  ASSERT_EQ(test::loadError("volume: {file: good.nii}\n", t.path.string()), "<no error>");
  auto write = [&](const std::string& name, std::string bytes) {
    std::ofstream(t.file(name), std::ios::binary) << bytes;
    return test::loadError("volume: {file: " + name + "}\n", t.path.string());
  };
  auto expectSays = [](const std::string& error, const std::string& what) {
    EXPECT_NE(error.find(what), std::string::npos) << "expected: " << what << "\ngot: " << error;
  };
  expectSays(write("cut.nii", good.substr(0, 200)), "cut.nii: not a readable NIfTI file: cut short: 200 bytes of its 348-byte NIfTI-1 header");
  std::string dim0 = good;
  dim0[40] = 9, dim0[41] = 0;  // little-endian int16, as nifticlib wrote it here
  expectSays(write("dim0.nii", dim0), "dim0.nii: not a readable NIfTI file: dim[0] = 9, must be in 1..7");
  // What nifticlib repairs without a word (found by review): a dim of 0 or below (a NIfTI-1
  // writer's 16-bit dim wrapped), and a single file's vox_offset below 352.
  std::string dim3 = good;
  dim3[46] = 0, dim3[47] = 0;
  expectSays(write("dim3.nii", dim3), "dim3.nii: not a readable NIfTI file: dim[3] = 0, must be at least 1");
  std::string wrapped = good;
  wrapped[44] = (char)0xf0, wrapped[45] = (char)0xff;  // -16
  expectSays(write("wrapped.nii", wrapped), "dim[2] = -16, must be at least 1");
  for (float offset : {0.0f, 100.0f, -5.0f}) {
    std::string moved = good;
    std::memcpy(moved.data() + 108, &offset, 4);
    expectSays(write("moved.nii", moved), "moved.nii: not a readable NIfTI file: vox_offset = " + fmt::format("{}", offset) +
                                              ": the voxels of a single-file NIfTI-1 start at byte 352 or later");
  }
  expectSays(write("text.nii", "a text file, not a volume, named .nii by mistake\n"),
             "text.nii: not a readable NIfTI file: its first 4 bytes give a header size of");
}

// A gzip stream that ends early says both sizes, as a short uncompressed file does; a stream
// cut mid-block names zlib's error without its "<fd:N>" (found by review: neither said a size).
TEST(NiftiHeader, AShortGzipStreamSaysItsSizes) {
  test::TempDir t("short-gzip");
  std::string bytes = nifti4x4x4(t.file("whole.nii"));
  ASSERT_EQ(bytes.size(), 352u + 128u);
  for (size_t i = 352; i < bytes.size(); ++i) bytes[i] = (char)(i * 2654435761u >> 13);  // incompressible
  gzFile z = gzopen(t.file("short.nii.gz").c_str(), "wb");
  ASSERT_NE(z, nullptr);
  ASSERT_EQ(gzwrite(z, bytes.data(), 452), 452);  // 100 of the 128 sample bytes
  gzclose(z);
  const std::string e = test::loadError("volume: {file: short.nii.gz}\n", t.path.string());
  EXPECT_NE(e.find("short.nii.gz: the compressed data holds 452 bytes decompressed but dims 4 x 4 x 4 x 2 bytes/voxel "
                   "after a header of 352 bytes need 480 bytes"), std::string::npos) << e;
  z = gzopen(t.file("cut.nii.gz").c_str(), "wb");
  ASSERT_NE(z, nullptr);
  ASSERT_EQ(gzwrite(z, bytes.data(), (unsigned)bytes.size()), (int)bytes.size());
  gzclose(z);
  std::filesystem::resize_file(t.file("cut.nii.gz"), std::filesystem::file_size(t.file("cut.nii.gz")) - 60);
  const std::string c = test::loadError("volume: {file: cut.nii.gz}\n", t.path.string());
  EXPECT_NE(c.find("cut.nii.gz: corrupt compressed data: unexpected end of file"), std::string::npos) << c;
  EXPECT_EQ(c.find("<fd:"), std::string::npos) << c;
}

}  // namespace
}  // namespace tessera
