// Raw volume files (little-endian uint8/uint16/float32, x fastest, no header): the whole
// volume or a window of it, read with positioned reads so a renderer's memory follows its
// bricks, not the file.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/volume.h"

namespace tessera {
namespace {

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": " + what);
}

void checkGeometry(const std::string& file, const std::array<int, 3>& dims, const std::array<double, 3>& sp) {
  for (int i = 0; i < 3; ++i) {
    if (dims[i] <= 0) fail(file, "dims must be positive, got " + std::to_string(dims[i]));
  }
  if (std::string p = spacingProblem(sp); !p.empty()) fail(file, p);
}

template <class T>
T readLE(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
  }
  return v;
}

// An open raw file of known dims and type.
class RawFile {
 public:
  explicit RawFile(const RawVolumeSpec& spec) : spec_(spec), ts_(voxelTypeSize(spec.type)) {
    const std::string& f = spec.file;
    checkGeometry(f, spec.dims, spec.spacing);
    if (spec.has_range && !(spec.range[0] < spec.range[1]))
      fail(f, "range must satisfy min < max, got [" + std::to_string(spec.range[0]) + ", " +
                  std::to_string(spec.range[1]) + "]");
    if (std::string p = notRegularFile(f); !p.empty()) fail(f, p);
    const uintmax_t expected = (uintmax_t)spec.dims[0] * spec.dims[1] * spec.dims[2] * ts_;
    std::error_code ec;
    const uintmax_t actual = std::filesystem::file_size(f, ec);
    if (ec) fail(f, "cannot read size: " + ec.message());
    if (actual != expected)
      fail(f, "file size is " + std::to_string(actual) + " bytes but dims " + std::to_string(spec.dims[0]) + " x " +
                  std::to_string(spec.dims[1]) + " x " + std::to_string(spec.dims[2]) + " x " + std::to_string(ts_) +
                  " bytes/voxel need " + std::to_string(expected) + " bytes");
    fd_ = ::open(f.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) fail(f, std::string("cannot open: ") + std::strerror(errno));
  }
  ~RawFile() { ::close(fd_); }
  RawFile(const RawFile&) = delete;
  RawFile& operator=(const RawFile&) = delete;

  // count voxels starting at linear voxel index `first`, converted to float into out, in
  // pieces of at most 16 MiB of file bytes; non-finite values are refused naming the voxel.
  void read(size_t first, size_t count, float* out) {
    const size_t piece = (16u << 20) / ts_;
    for (size_t done = 0; done < count; done += piece) readPiece(first + done, std::min(piece, count - done), out + done);
  }

  // The data's min and max, streaming the file.
  std::array<double, 2> scanRange() {
    const size_t total = (size_t)spec_.dims[0] * spec_.dims[1] * spec_.dims[2];
    const size_t chunk = (16u << 20) / ts_;
    std::vector<float> vals(std::min(chunk, total));
    float mn = INFINITY, mx = -INFINITY;
    for (size_t first = 0; first < total; first += chunk) {
      const size_t n = std::min(chunk, total - first);
      readPiece(first, n, vals.data());
      for (size_t i = 0; i < n; ++i) mn = std::min(mn, vals[i]), mx = std::max(mx, vals[i]);
    }
    return {mn, mx};
  }

 private:
  void readPiece(size_t first, size_t count, float* out) {
    buf_.resize(count * ts_);
    size_t done = 0;
    const off_t at = (off_t)(first * ts_);
    while (done < buf_.size()) {
      const ssize_t r = ::pread(fd_, buf_.data() + done, buf_.size() - done, at + (off_t)done);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) fail(spec_.file, r < 0 ? std::string("read failed: ") + std::strerror(errno) : "read failed: file shrank");
      done += (size_t)r;
    }
    const unsigned char* p = buf_.data();
    if (spec_.type == VoxelType::UInt8) {
      for (size_t i = 0; i < count; ++i) out[i] = (float)p[i];
    } else if (spec_.type == VoxelType::UInt16) {
      for (size_t i = 0; i < count; ++i) out[i] = (float)readLE<uint16_t>(p + 2 * i);
    } else {
      for (size_t i = 0; i < count; ++i) {
        out[i] = readLE<float>(p + 4 * i);
        if (!std::isfinite(out[i])) nonFinite(first + i, out[i]);
      }
    }
  }

  [[noreturn]] void nonFinite(size_t i, float x) const {
    const size_t nx = spec_.dims[0], ny = spec_.dims[1];
    fail(spec_.file, "non-finite value " + std::to_string(x) + " at voxel (" + std::to_string(i % nx) + ", " +
                         std::to_string(i / nx % ny) + ", " + std::to_string(i / (nx * ny)) + "), linear index " +
                         std::to_string(i));
  }

  const RawVolumeSpec& spec_;
  size_t ts_;
  int fd_ = -1;
  std::vector<unsigned char> buf_;
};

}  // namespace

Volume loadRawVolume(const RawVolumeSpec& spec) {
  return loadRawVolume(spec, VoxelBox{{0, 0, 0}, spec.dims});
}

Volume loadRawVolume(const RawVolumeSpec& spec, const VoxelBox& box) {
  RawFile file(spec);
  const auto& n = spec.dims;
  if (std::string p = windowProblem(n, box); !p.empty()) fail(spec.file, p);
  Volume v;
  for (int a = 0; a < 3; ++a) v.dims[a] = box.hi[a] - box.lo[a];
  // Before allocating: a sparse or huge file would otherwise end in a bare std::bad_alloc.
  if (std::string p = memoryProblem(v.dims, 0); !p.empty()) fail(spec.file, p);
  v.origin = box.lo;
  v.whole_dims = n;
  v.spacing = spec.spacing;
  v.values.resize(v.voxelCount());
  // Rows of the window; whole rows (and whole slices) are contiguous in the file and read at once.
  const bool full_x = v.dims[0] == n[0], full_xy = full_x && v.dims[1] == n[1];
  const int rows_per_read = full_xy ? v.dims[1] * v.dims[2] : full_x ? v.dims[1] : 1;
  const size_t per_read = (size_t)v.dims[0] * rows_per_read;
  for (size_t row = 0; row < (size_t)v.dims[1] * v.dims[2]; row += rows_per_read) {
    const int y = box.lo[1] + (int)(row % v.dims[1]), z = box.lo[2] + (int)(row / v.dims[1]);
    file.read(box.lo[0] + (size_t)n[0] * (y + (size_t)n[1] * z), per_read, &v.values[row * v.dims[0]]);
  }
  std::array<double, 2> data{INFINITY, -INFINITY};
  if (v.isWindow() && !spec.has_range) {
    data = file.scanRange();  // the whole volume's, so every window normalises alike
  } else {
    for (float x : v.values) data[0] = std::min(data[0], (double)x), data[1] = std::max(data[1], (double)x);
  }
  // Like ParaView: with no declared range, colours and opacity span the data's own values.
  const double lo = spec.has_range ? spec.range[0] : data[0], hi = spec.has_range ? spec.range[1] : data[1];
  v.data_range = data;  // a window with a declared range knows only its own values
  v.mapped_range = {lo, hi};
  // Normalise in double; a constant volume (lo == hi) maps to 0 everywhere.
  const double scale = hi > lo ? 1.0 / (hi - lo) : 0.0;
  for (float& x : v.values) x = (float)std::clamp((x - lo) * scale, 0.0, 1.0);
  return v;
}

}  // namespace tessera
