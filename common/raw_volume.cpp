// Volume samples in a file (x fastest; any voxel type, either byte order, after an offset, plain
// or gzip-compressed): the whole volume or a window of it, read with positioned reads (or a forward
// stream through compressed data) so a renderer's memory follows its bricks, not the file.
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <zlib.h>

#include "common/io/volume_files.h"  // sliceBytes
#include "common/lanes.h"
#include "common/sample_convert.h"
#include "common/volume.h"

namespace tessera {
namespace {

std::atomic<uint64_t> samples_read{0};
std::atomic<uint64_t> bytes_inflated{0};  // what zlib decompressed, skipped bytes included

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": " + what);
}

void checkGeometry(const std::string& file, const std::array<int, 3>& dims, const std::array<double, 3>& sp) {
  for (int i = 0; i < 3; ++i)
    if (dims[i] <= 0) fail(file, "dims must be positive, got " + std::to_string(dims[i]));
  if (std::string p = spacingProblem(sp); !p.empty()) fail(file, p);
}

}  // namespace

// An open raw file of known dims and type (not in the anonymous namespace: a RawVolumeReader holds one).
class RawFile {
 public:
  explicit RawFile(const RawVolumeSpec& spec) : spec_(spec), ts_(voxelTypeSize(spec.type)) {
    const std::string& f = spec.file;
    // Values float32 may round (wide types, a header's scaling) are held relative to a value (resetRef).
    const auto scaled = [](double slope, double inter) { return slope != 1 || inter != 0; };
    relative_ = spec.type == VoxelType::Int32 || spec.type == VoxelType::UInt32 || spec.type == VoxelType::Float64 ||
                scaled(spec.slope, spec.inter) ||
                std::any_of(spec.slices.begin(), spec.slices.end(), [&](const SliceFile& s) { return scaled(s.slope, s.inter); });
    checkGeometry(f, spec.dims, spec.spacing);
    if (spec.has_range && !(spec.range[0] < spec.range[1]))
      fail(f, "range must satisfy min < max, got [" + std::to_string(spec.range[0]) + ", " + std::to_string(spec.range[1]) + "]");
    if (!spec.slices.empty()) {  // slice by slice: a DICOM series, a TIFF stack
      if (spec.slices.size() != (size_t)spec.dims[2])
        fail(f, std::to_string(spec.slices.size()) + " slices for dims[2] = " + std::to_string(spec.dims[2]));
      return;
    }
    if (std::string p = notRegularFile(spec.samples()); !p.empty()) fail(spec.samples(), p);
    // A compressed file's size says nothing; a short stream is found when it is read.
    const uintmax_t expected = (uintmax_t)spec.dims[0] * spec.dims[1] * spec.dims[2] * ts_ + spec.offset;
    std::error_code ec;
    const uintmax_t actual = std::filesystem::file_size(spec.samples(), ec);
    if (ec) fail(spec.samples(), "cannot read size: " + ec.message());
    if (!spec.gzip && actual != expected && (spec.format == VolumeFormat::Raw || actual < expected))
      fail(spec.samples(), "file size is " + std::to_string(actual) + " bytes but " + sizeNeeded(spec));
    if (spec.gzip) {
      const int fd = ::open(spec.samples().c_str(), O_RDONLY | O_CLOEXEC);
      if (fd < 0 || ::lseek(fd, (off_t)spec.gzip_start, SEEK_SET) < 0 || !(gz_ = gzdopen(fd, "rb"))) {
        if (fd >= 0) ::close(fd);
        fail(spec.samples(), std::string("cannot open: ") + std::strerror(errno));
      }
      gzbuffer(gz_, 1 << 18);
    } else {
      fd_ = ::open(spec.samples().c_str(), O_RDONLY | O_CLOEXEC);
      if (fd_ < 0) fail(spec.samples(), std::string("cannot open: ") + std::strerror(errno));
      // A series step is read once per pass and a series is often larger than memory: what
      // is not in the page cache already bypasses it (some file systems refuse O_DIRECT:
      // then buffered).
      if (spec.read_once) direct_fd_ = ::open(spec.samples().c_str(), O_RDONLY | O_CLOEXEC | O_DIRECT);
    }
  }
  ~RawFile() {
    if (gz_) gzclose(gz_);
    if (fd_ >= 0) ::close(fd_);
    if (direct_fd_ >= 0) ::close(direct_fd_);
  }
  RawFile(const RawFile&) = delete;
  RawFile& operator=(const RawFile&) = delete;

  // count voxels starting at linear voxel index `first`, converted to float into out, in
  // pieces of at most 256 KiB of file bytes; non-finite values are refused naming the voxel.
  // Each piece then goes through then(piece, n) while it is still in cache: a time step's
  // samples cross memory once on their way in, not once per pass.
  template <class Then>
  void read(size_t first, size_t count, float* out, Then&& then) {
    const size_t piece = kPieceBytes / ts_;
    run_end_ = spec_.offset + (first + count) * ts_, run_bytes_ = count * ts_;
    for (size_t done = 0; done < count; done += piece) {
      const size_t n = std::min(piece, count - done);
      readPiece(first + done, n, out + done);
      then(out + done, n);
    }
  }

  // What samples are held relative to (0 for those float32 holds exactly): r, or (NaN) the next read's first.
  void resetRef(double r) { ref_ = relative_ ? r : 0.0; }
  double ref() const { return std::isnan(ref_) ? 0.0 : ref_; }

  // The data's min and max (in its own units), streaming the file.
  std::array<double, 2> scanRange() {
    const size_t total = (size_t)spec_.dims[0] * spec_.dims[1] * spec_.dims[2];
    const size_t chunk = kPieceBytes / ts_;
    std::vector<float> vals(std::min(chunk, total));
    float mn = INFINITY, mx = -INFINITY;
    run_end_ = spec_.offset + total * ts_, run_bytes_ = total * ts_;
    for (size_t first = 0; first < total; first += chunk) {
      const size_t n = std::min(chunk, total - first);
      readPiece(first, n, vals.data());
      for (size_t i = 0; i < n; ++i) mn = std::min(mn, vals[i]), mx = std::max(mx, vals[i]);
    }
    return {mn + ref(), mx + ref()};
  }

 private:
  void readPiece(size_t first, size_t count, float* out) {
    if (!spec_.slices.empty()) return readSlices(first, count, out);
    const uint64_t at = spec_.offset + first * ts_;
    // Native float32 without scaling (what simulations write) is read straight into place:
    // no copy, no conversion pass (a time step's preparation is on the renderers' cores).
    const bool direct = spec_.type == VoxelType::Float32 && spec_.big_endian == (std::endian::native == std::endian::big) &&
                        spec_.slope == 1 && spec_.inter == 0;
    unsigned char* dst = direct ? reinterpret_cast<unsigned char*>(out) : (buf_.resize(count * ts_), buf_.data());
    if (gz_) readGzip(at, dst, count * ts_);
    else readPlain(at, dst, count * ts_);
    samples_read += count * ts_;
    if (direct) return checkFinite(first, count, out);
    convertRelative({spec_.slope, spec_.inter, spec_.big_endian}, count, out);
    checkFinite(first, count, out);
  }

  // A DICOM series or a TIFF stack: a piece may span slices (dicom_series.cpp, tiff_stack.cpp).
  void readSlices(size_t first, size_t count, float* out) {
    if (!slices_) slices_ = sliceBytes(spec_);
    const size_t per_slice = (size_t)spec_.dims[0] * spec_.dims[1];
    while (count > 0) {
      const size_t z = first / per_slice, in = first % per_slice, n = std::min(count, per_slice - in);
      buf_.resize(n * ts_);
      const uint64_t decoded = slices_->decoded_bytes;
      slices_->read(z, in, n, buf_.data());
      bytes_inflated += slices_->decoded_bytes - decoded;
      const SliceFile& s = spec_.slices[z];
      convertRelative({s.slope, s.inter, false}, n, out);
      samples_read += n * ts_;
      checkFinite(first, n, out);
      first += n, count -= n, out += n;
    }
  }

  // n samples of buf_ to floats, relative to the reference value (the first sets an unset one).
  void convertRelative(samples::Scaling sc, size_t n, float* out) {
    if (std::isnan(ref_)) ref_ = samples::firstValue(spec_.type, buf_.data(), sc);
    sc.ref = ref_;
    samples::convertAll(spec_.type, buf_.data(), n, sc, out);
  }

  // One vector test over the piece; the voxel is looked for only when there is one.
  void checkFinite(size_t first, size_t count, const float* out) const {
    lanes::I4 bad{};
    size_t i = 0;
    for (; i + 4 <= count; i += 4) bad |= lanes::nonFinite(lanes::load(out + i));
    for (; i < count; ++i) bad[0] |= !std::isfinite(out[i]);
    if (!lanes::any(bad)) return;
    for (i = 0; i < count; ++i)
      if (!std::isfinite(out[i])) fail(spec_.samples(), samples::nonFiniteProblem(spec_, first + i, out[i]));
  }

  void readPlain(uint64_t at, unsigned char* dst, size_t bytes) {
    // Direct only for long runs (a renderer's slab): short rows would each wait for the device.
    if (direct_fd_ >= 0 && (inChunk(at, bytes) || (run_bytes_ >= kPieceBytes && !cached(at, bytes))))
      return readDirect(at, dst, bytes);
    preadAll(fd_, at, dst, bytes, bytes);
  }

  // Reads up to `bytes` at `at` into dst until at least `need` arrived (a direct read may ask
  // past the end of the file); returns how many did, or 0 when a direct read is refused for
  // its alignment (EINVAL).
  size_t preadAll(int fd, uint64_t at, unsigned char* dst, size_t bytes, size_t need) {
    size_t done = 0;
    while (done < need) {
      const ssize_t r = ::pread(fd, dst + done, bytes - done, (off_t)(at + done));
      if (r < 0 && errno == EINTR) continue;
      if (r < 0 && errno == EINVAL && fd == direct_fd_) return 0;
      if (r <= 0) fail(spec_.samples(), r < 0 ? std::string("read failed: ") + std::strerror(errno) : "read failed: file shrank");
      done += (size_t)r;
    }
    return done;
  }

  // Whether every page of the range is in the page cache (then a buffered read is a copy).
  // mincore answers only for files the caller owns or may write (else: never cached, so
  // read directly); preadv2's RWF_NOWAIT would start readahead into the cache on a miss.
  bool cached(uint64_t at, size_t bytes) const {
    const uint64_t page = (uint64_t)::sysconf(_SC_PAGESIZE), start = at / page * page;
    const size_t len = (size_t)(at + bytes - start);
    void* map = ::mmap(nullptr, len, PROT_READ, MAP_SHARED, fd_, (off_t)start);
    if (map == MAP_FAILED) return false;
    std::vector<unsigned char> in((len + page - 1) / page);
    const bool all = ::mincore(map, len, in.data()) == 0 && std::all_of(in.begin(), in.end(), [](unsigned char c) { return c & 1; });
    ::munmap(map, len);
    return all;
  }

  bool inChunk(uint64_t at, size_t bytes) const { return at >= chunk_lo_ && at + bytes <= chunk_hi_; }

  // O_DIRECT reads of aligned chunks of up to kChunkBytes (within the current run), served
  // piece by piece: a synchronous read waits for the device and then for a core busy ray
  // casting, so few large reads (256 KiB ones took a 512^3 renderer 1.2 s a step).
  void readDirect(uint64_t at, unsigned char* dst, size_t bytes) {
    struct Chunk {  // one a thread: the prefetch thread's and a render thread's
      std::unique_ptr<unsigned char, Free> bytes{static_cast<unsigned char*>(std::aligned_alloc(kAlign, kChunkBytes))};
      const RawFile* filled_by = nullptr;
    };
    thread_local Chunk chunk;
    if (!chunk.bytes) throw std::bad_alloc();
    if (chunk.filled_by != this || !inChunk(at, bytes)) {
      const uint64_t start = at / kAlign * kAlign, want = std::max<uint64_t>(run_end_, at + bytes);
      const size_t len = (size_t)std::min<uint64_t>((want + kAlign - 1) / kAlign * kAlign - start, kChunkBytes);
      chunk.filled_by = nullptr;  // until the read succeeds
      const size_t got = preadAll(direct_fd_, start, chunk.bytes.get(), len, (size_t)(at + bytes - start));
      if (got == 0) {  // an alignment this file system refuses: buffered reads from now on
        ::close(direct_fd_);
        direct_fd_ = -1;
        preadAll(fd_, at, dst, bytes, bytes);
        return;
      }
      chunk.filled_by = this;
      chunk_lo_ = start;
      chunk_hi_ = start + got;
    }
    std::memcpy(dst, chunk.bytes.get() + (at - chunk_lo_), bytes);
  }

  // Windows are read in file order, so the stream only moves forward (zlib decompresses
  // what it skips); memory stays one piece.
  void readGzip(uint64_t at, unsigned char* dst, size_t bytes) {
    const uint64_t now = (uint64_t)gztell(gz_);
    bytes_inflated += (at >= now ? at - now : at) + bytes;  // a seek back restarts the stream
    // A forward seek past the end succeeds lazily: the stream's end is where gztell stops.
    const int r = now != at && gzseek(gz_, (z_off_t)at, SEEK_SET) < 0 ? -1 : gzread(gz_, dst, (unsigned)bytes);
    if (r != (int)bytes) {
      int err = 0;
      std::string msg = gzerror(gz_, &err);
      if (msg.rfind("<fd:", 0) == 0 && msg.find(">: ") != std::string::npos) msg.erase(0, msg.find(">: ") + 3);
      fail(spec_.samples(), err ? "corrupt compressed data: " + msg : shortStream((uint64_t)gztell(gz_), at + bytes));
    }
  }

  // A stream that ended at byte `ended` where bytes up to `needed` were read (said by review).
  std::string shortStream(uint64_t ended, uint64_t needed) const {
    const uint64_t volume = (uint64_t)spec_.dims[0] * spec_.dims[1] * spec_.dims[2] * ts_;
    const uint64_t step = volume && needed > spec_.offset ? (needed - spec_.offset - 1) / volume : 0;
    return "the compressed data holds " + std::to_string(ended) + " bytes decompressed but " + sizeNeeded(spec_, step);
  }

  static constexpr size_t kPieceBytes = 256u << 10;  // well inside a core's L2
  static constexpr size_t kAlign = 4096;             // O_DIRECT's offsets, sizes and memory
  static constexpr size_t kChunkBytes = 4u << 20;    // a direct read; > kPieceBytes + 2 kAlign
  struct Free {
    void operator()(unsigned char* p) const { std::free(p); }
  };
  const RawVolumeSpec& spec_;
  size_t ts_;
  bool relative_ = false;
  double ref_ = 0;  // see resetRef
  int fd_ = -1, direct_fd_ = -1;
  uint64_t run_end_ = 0, run_bytes_ = 0;  // file byte after the samples being read, and their size
  uint64_t chunk_lo_ = 0, chunk_hi_ = 0;  // file bytes in this thread's chunk, when this filled it last
  gzFile gz_ = nullptr;
  std::vector<unsigned char> buf_;
  std::unique_ptr<SliceBytes> slices_;  // a DICOM series' or a TIFF stack's slices
};

// The file stays open between windows; with no declared range the whole file's min..max is
// streamed once, for the first window, and every later window normalises with it.
// A later window may lie further on in the file (`shift`, a 4-D file's later step): the
// spec's offset moves with it, and the scan is the shifted samples' own.
struct RawVolumeReader::Open {
  RawVolumeSpec spec;  // before file, which refers to it
  RawFile file;
  uint64_t base;       // the offset the reader was opened with
  std::optional<std::array<double, 2>> scanned;
  uint64_t scanned_shift = 0;
  std::optional<uint64_t> ref_shift;  // the shift the file's reference value is for
  explicit Open(RawVolumeSpec s) : spec(std::move(s)), file(spec), base(spec.offset) {}
};

RawVolumeReader::RawVolumeReader(RawVolumeSpec spec) : open_(std::make_unique<Open>(std::move(spec))) {}
RawVolumeReader::~RawVolumeReader() = default;

uint64_t volumeSamplesRead() { return samples_read; }
uint64_t volumeBytesInflated() { return bytes_inflated; }

Volume loadRawVolume(const RawVolumeSpec& spec) {
  return loadRawVolume(spec, VoxelBox{{0, 0, 0}, spec.dims});
}

Volume loadRawVolume(const RawVolumeSpec& spec, const VoxelBox& box, std::vector<float> storage) {
  return RawVolumeReader(spec).read(box, std::move(storage));
}

Volume RawVolumeReader::read(const VoxelBox& box, std::vector<float> storage, uint64_t shift) {
  return read(box, std::move(storage), shift, true);
}

Volume RawVolumeReader::readValues(const VoxelBox& box) { return read(box, {}, 0, false); }

Volume RawVolumeReader::read(const VoxelBox& box, std::vector<float> storage, uint64_t shift, bool map) {
  const RawVolumeSpec& spec = open_->spec;
  RawFile& file = open_->file;
  open_->spec.offset = open_->base + shift;
  if (open_->scanned && open_->scanned_shift != shift) open_->scanned.reset();
  // Samples held relative to the declared range's low end, else to the step's first sample.
  if (open_->ref_shift != shift) file.resetRef(spec.has_range ? spec.range[0] : NAN), open_->ref_shift = shift;
  const auto& n = spec.dims;
  if (std::string p = windowProblem(n, box); !p.empty()) fail(spec.file, p);
  Volume v;
  for (int a = 0; a < 3; ++a) v.dims[a] = box.hi[a] - box.lo[a];
  // Before allocating: a sparse or huge file would otherwise end in a bare std::bad_alloc.
  if (std::string p = memoryProblem(v.dims); !p.empty()) fail(spec.file, p);
  v.origin = box.lo;
  v.whole_dims = n;
  v.spacing = spec.spacing;
  v.values = std::move(storage);
  v.values.resize(v.voxelCount());  // no work when the storage has that size: every sample is read
  // The range to normalise with: declared, else the whole volume's (every window normalises
  // alike; streamed first), else, for the whole volume, its values' once read.
  std::array<double, 2> data{INFINITY, -INFINITY};
  if (map && v.isWindow() && !spec.has_range) {
    if (!open_->scanned) open_->scanned = file.scanRange(), open_->scanned_shift = shift;
    data = *open_->scanned;
  }
  const bool known = map && (spec.has_range || v.isWindow());
  // Like ParaView: with no declared range, colours and opacity span the data's own values.
  double lo = spec.has_range ? spec.range[0] : data[0], hi = spec.has_range ? spec.range[1] : data[1];
  float mn = INFINITY, mx = -INFINITY;
  auto normalise = [&](float* x, size_t count) {  // in double; a constant volume (lo == hi) maps to 0
    const double l = lo - file.ref(), h = hi - file.ref();  // x holds value - ref
    const double scale = h > l ? 1.0 / (h - l) : 0.0;
    using lanes::D4, lanes::F4;
    const D4 dlo = {l, l, l, l}, dscale = {scale, scale, scale, scale};
    const F4 zero = lanes::splat(0), one = lanes::splat(1);
    F4 vmn = lanes::splat(mn), vmx = lanes::splat(mx);
    size_t i = 0;
    for (; i + 4 <= count; i += 4) {  // as the scalar loop below, four at a time
      const F4 f = lanes::load(x + i);
      vmn = lanes::min(vmn, f), vmx = lanes::max(vmx, f);
      // Clamped after rounding to float, which is the same (0 and 1 are floats; only a -0
      // can come out +0) and stays in four-lane registers.
      const F4 g = __builtin_convertvector((__builtin_convertvector(f, D4) - dlo) * dscale, F4);
      lanes::store(x + i, g > zero ? (g < one ? g : one) : zero);
    }
    mn = lanes::hmin(vmn), mx = lanes::hmax(vmx);
    for (; i < count; ++i) {
      mn = std::min(mn, x[i]), mx = std::max(mx, x[i]);
      x[i] = normaliseSample(x[i], l, h);
    }
  };
  // Rows of the window; whole rows (and whole slices) are contiguous in the file and read at once.
  const bool full_x = v.dims[0] == n[0], full_xy = full_x && v.dims[1] == n[1];
  // size_t: a window's rows (y * z) can pass 2^31 (a 4 GiB file of 1 x 65536 x 65536 wrapped to 0).
  const size_t rows_per_read = full_xy ? (size_t)v.dims[1] * v.dims[2] : full_x ? (size_t)v.dims[1] : 1;
  const size_t per_read = (size_t)v.dims[0] * rows_per_read;
  for (size_t row = 0; row < (size_t)v.dims[1] * v.dims[2]; row += rows_per_read) {
    const int y = box.lo[1] + (int)(row % v.dims[1]), z = box.lo[2] + (int)(row / v.dims[1]);
    file.read(box.lo[0] + (size_t)n[0] * (y + (size_t)n[1] * z), per_read, &v.values[row * v.dims[0]], [&](float* x, size_t k) {
      if (known) normalise(x, k);
    });
  }
  if (!known) {  // the whole volume without a declared range: its own values set it
    for (float x : v.values) data[0] = std::min(data[0], (double)x), data[1] = std::max(data[1], (double)x);
    data = {data[0] + file.ref(), data[1] + file.ref()};
    lo = data[0], hi = data[1];
    if (map) normalise(v.values.data(), v.values.size());
  }
  // Mapped with a declared range: the window's own values, seen while normalising.
  v.data_range = map && spec.has_range ? std::array<double, 2>{mn + file.ref(), mx + file.ref()} : data;
  v.mapped_range = {lo, hi};
  if (!map) v.value_offset = file.ref();
  return v;
}

}  // namespace tessera
