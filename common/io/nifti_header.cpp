// NIfTI-1/2 headers through nifticlib (see volume_files.h).
#include <nifti2_io.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <zlib.h>

#include "common/io/volume_files.h"

namespace tessera {
namespace {

bool startsWithGzipMagic(const std::string& path) {
  unsigned char m[2] = {0, 0};
  std::ifstream in(path, std::ios::binary);
  return in.read(reinterpret_cast<char*>(m), 2) && m[0] == 0x1f && m[1] == 0x8b;
}

// What is wrong with `path`'s header, from its bytes as stored (gzread reads a plain file as it
// is): why nifticlib refused it (it says only "bad header" on stderr), or what it would repair
// without a word. Empty when the bytes show nothing wrong; then `given` (if asked for) says which
// spacings pixdim[1..3] the header gives (nifticlib turns 0 and NaN into 1 when it reads).
std::string headerProblem(const std::string& path, std::array<bool, 3>* given = nullptr) {
  unsigned char h[540] = {};
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) return "";
  const int n = gzread(f, h, sizeof h);
  int err = Z_OK;
  const std::string zmsg = n < 4 ? gzerror(f, &err) : "";
  gzclose(f);
  // A compressed stream cut short or corrupt is said as such, not as a file of no bytes.
  if (n < 4 && err != Z_OK) return "its gzip stream is corrupt or cut short (" + zmsg + ")";
  if (n < 4) return "only " + std::to_string(std::max(n, 0)) + " bytes: not a NIfTI file";
  auto i32 = [&](int at, bool swap) {
    uint32_t v = (uint32_t)h[at] | (uint32_t)h[at + 1] << 8 | (uint32_t)h[at + 2] << 16 | (uint32_t)h[at + 3] << 24;
    return (int32_t)(swap ? __builtin_bswap32(v) : v);
  };
  auto i16 = [&](int at, bool swap) {
    const uint16_t v = (uint16_t)(h[at] | h[at + 1] << 8);
    return (int16_t)(swap ? __builtin_bswap16(v) : v);
  };
  auto i64 = [&](int at, bool swap) {
    uint64_t v = 0;
    for (int b = 7; b >= 0; --b) v = v << 8 | h[at + b];
    return (int64_t)(swap ? __builtin_bswap64(v) : v);
  };
  bool swap = false;
  int version = 0;
  for (bool sw : {false, true}) {
    if (i32(0, sw) == 348) version = 1, swap = sw;
    if (i32(0, sw) == 540) version = 2, swap = sw;
  }
  if (!version)
    return "its first 4 bytes give a header size of " + std::to_string(i32(0, false)) +
           ", where a NIfTI-1 header has 348 and a NIfTI-2 header 540: not a NIfTI file";
  const int size = version == 1 ? 348 : 540;
  if (n < size)
    return "cut short: " + std::to_string(n) + " bytes of its " + std::to_string(size) + "-byte NIfTI-" +
           std::to_string(version) + " header";
  const int64_t dim0 = version == 1 ? i16(40, swap) : i64(16, swap);
  if (dim0 < 1 || dim0 > 7) return "dim[0] = " + std::to_string(dim0) + ", must be in 1..7";
  for (int d = 1; d <= dim0; ++d) {  // a time or vector dim of 0 is read as 1, as nifticlib does
    const int64_t v = version == 1 ? i16(40 + 2 * d, swap) : i64(16 + 8 * d, swap);
    if (v < (d <= 3 ? 1 : 0)) return "dim[" + std::to_string(d) + "] = " + std::to_string(v) + ", must be at least " + (d <= 3 ? "1" : "0");
  }
  const int datatype = version == 1 ? i16(70, swap) : i16(12, swap);
  if (!nifti_is_valid_datatype(datatype)) return "datatype " + std::to_string(datatype) + " is not a NIfTI type code";
  // A single file's voxels follow its header and 4 extension bytes; nifticlib reads a smaller
  // vox_offset (0, negative) as the header's end, 4 bytes early: every voxel shifted.
  const bool single = std::memcmp(version == 1 ? h + 344 : h + 4, version == 1 ? "n+1" : "n+2", 4) == 0;
  // A float (NIfTI-1) or double (NIfTI-2) field.
  auto real = [&](int at1, int at2) {
    if (version == 2) return std::bit_cast<double>(i64(at2, swap));
    return (double)std::bit_cast<float>(i32(at1, swap));
  };
  const double offset = version == 1 ? (double)std::bit_cast<float>(i32(108, swap)) : (double)i64(168, swap);
  if (single && !(offset >= size + 4))
    return "vox_offset = " + fmt::format("{}", offset) + ": the voxels of a single-file NIfTI-" + std::to_string(version) +
           " start at byte " + std::to_string(size + 4) + " or later";
  for (int a = 0; given && a < 3; ++a) {
    const double p = real(76 + 4 * (a + 1), 104 + 8 * (a + 1));
    (*given)[a] = p != 0 && std::isfinite(p);
  }
  return "";
}

}  // namespace

RawVolumeSpec readNiftiHeader(const std::string& path, int* time_steps) {
  auto fail = [&](const std::string& what) -> RawVolumeSpec { throw std::runtime_error(path + ": " + what); };
  nifti_set_debug_level(0);  // its messages go to stderr; ours name the file and field
  std::unique_ptr<nifti_image, void (*)(nifti_image*)> nim(nifti_image_read(path.c_str(), 0), nifti_image_free);
  // nifticlib also repairs what it reads: a dim of 0 or below becomes 1 (the rest of the file
  // ignored), a .nii's vox_offset below 352 the header's end. Either renders the wrong voxels
  // without a word, so the header's own bytes are checked too (found by review).
  std::array<bool, 3> given{true, true, true};
  if (nim) {
    std::unique_ptr<char, void (*)(void*)> hdr(nifti_findhdrname(path.c_str()), std::free);
    if (std::string why = headerProblem(hdr ? hdr.get() : path, &given); !why.empty())
      return fail("not a readable NIfTI file: " + why);
  }
  if (!nim) {
    // nifticlib decompresses by the name only: a gzipped file named .nii reads as a bad header.
    if (startsWithGzipMagic(path) && !nifti_is_gzfile(path.c_str()))
      return fail("gzip-compressed, but its name does not end in .gz (nifticlib goes by the name: rename it " +
                  std::filesystem::path(path).filename().string() + ".gz)");
    // Given the .img of a pair, its header is the .hdr beside it.
    char* hdr = nifti_findhdrname(path.c_str());
    const std::string header = hdr ? hdr : path;
    std::free(hdr);
    if (std::string why = headerProblem(header); !why.empty())
      return fail("not a readable NIfTI file: " + (header != path ? std::filesystem::path(header).filename().string() + ": " : "") + why);
    return fail("not a readable NIfTI-1 or NIfTI-2 file (missing, cut short, or a bad header)");
  }
  RawVolumeSpec s;
  s.format = VolumeFormat::Nifti;
  s.file = path;
  // Axes beyond dim[0] do not count (a 2-D file may leave dim[3] = 0): they are one voxel.
  auto used = [&](int axis) { return axis <= nim->dim[0]; };
  const int64_t n[3] = {used(1) ? nim->dim[1] : 1, used(2) ? nim->dim[2] : 1, used(3) ? nim->dim[3] : 1};
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 1 || n[a] > 65536) fail("dim[" + std::to_string(a + 1) + "] = " + std::to_string(n[a]) + ", must be in 1..65536");
    s.dims[a] = (int)n[a];
  }
  // dim[4..7] beyond dim[0] are unset (0 or 1): only those within dim[0] count. dim[4] is
  // time; dim[5..7] (vector components and more) are not rendered.
  int64_t more = 1, steps = 1;
  std::string extra;
  for (int i = 4; i <= 7; ++i) {
    const int64_t d = i <= nim->dim[0] ? std::max<int64_t>(1, nim->dim[i]) : 1;
    (i == 4 && time_steps ? steps : more) *= d;
    extra += (i > 4 ? ", " : "") + std::to_string(d);
  }
  if (more != 1)
    fail("holds " + std::to_string(more) + " volumes (dim[4..7] = " + extra + "); Tessera renders one 3-D volume" +
         (time_steps ? " per time step (dim[4])" : ""));
  if (steps > 1000000) fail("dim[4] = " + std::to_string(steps) + " time steps, must be in 1..1000000");
  if (time_steps) *time_steps = (int)steps;
  switch (nim->datatype) {
    case DT_UINT8: s.type = VoxelType::UInt8; break;
    case DT_INT8: s.type = VoxelType::Int8; break;
    case DT_UINT16: s.type = VoxelType::UInt16; break;
    case DT_INT16: s.type = VoxelType::Int16; break;
    case DT_UINT32: s.type = VoxelType::UInt32; break;
    case DT_INT32: s.type = VoxelType::Int32; break;
    case DT_FLOAT32: s.type = VoxelType::Float32; break;
    case DT_FLOAT64: s.type = VoxelType::Float64; break;
    default:
      fail(std::string("datatype ") + std::to_string(nim->datatype) + " (" + nifti_datatype_string(nim->datatype) +
           ") is not a scalar type Tessera renders (uint8, int8, uint16, int16, uint32, int32, float32, float64)");
  }
  const double d[3] = {used(1) ? nim->dx : 1, used(2) ? nim->dy : 1, used(3) ? nim->dz : 1};
  for (int a = 0; a < 3; ++a) {
    // A spacing of 0 (or NaN) is common in hand-made headers: 1, and a warning says so (as a
    // TIFF's missing one). pixdim's sign belongs to orientation. Checked by the scene parser,
    // after the scene's volume.spacing (which may replace a bad one).
    const bool known = d[a] != 0 && std::isfinite(d[a]) && (!used(a + 1) || given[a]);
    s.spacing[a] = known ? std::fabs(d[a]) : 1.0;
    s.spacing_known[a] = known || !used(a + 1);
  }
  if (nim->scl_slope != 0 && std::isfinite(nim->scl_slope) && std::isfinite(nim->scl_inter)) {
    s.slope = nim->scl_slope;
    s.inter = nim->scl_inter;
  }
  if (nim->iname && path != nim->iname) {  // .hdr + .img: whichever of .img and .img.gz is there, as nifticlib looks
    std::unique_ptr<char, void (*)(void*)> img(nifti_findimgname(path.c_str(), nim->nifti_type), std::free);
    if (!img) fail("a header without its image file (" + std::string(nim->iname) + " or .img.gz)");
    s.data_file = img.get();
  }
  s.offset = (uint64_t)std::max<int64_t>(0, nim->iname_offset);
  s.big_endian = nim->byteorder == 2;  // MSB_FIRST (nifti1_io.h; nifti2_io.h lacks the name)
  s.gzip = nifti_is_gzfile(s.samples().c_str());
  return s;
}

}  // namespace tessera
