// TIFF stacks through libtiff: a multi-page TIFF (one slice a page, as Fiji and most
// microscopes and micro-CT scanners save a stack) or a folder of single-page TIFFs (one slice
// a file, in natural name order: slice2 before slice10). Grayscale pages of one size and
// sample type; ImageJ's or OME's metadata gives the spacing (tiff_metadata.cpp). A slice is read by the strips or
// tiles that hold the part a window needs, decoded by libtiff (any compression it decodes).
#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/io/tiff_metadata.h"
#include "common/io/volume_files.h"

namespace tessera {
namespace {
namespace tiff {  // a unity build joins this file's helpers with others' (fail, ...)

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& file, const std::string& what) { throw std::runtime_error(file + ": " + what); }

// libtiff reports through global handlers that print; its last error and warning on this
// thread go into the exceptions that name the file instead. Warnings (unknown tags, common in
// microscopes' files) matter only where a page list ends early (a loop in it).
thread_local std::string last_error, last_warning;
void onError(const char*, const char* fmt, va_list ap) {
  char buf[512];
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  last_error = buf;
}
void onWarning(const char*, const char* fmt, va_list ap) {
  char buf[512];
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  last_warning = buf;
}

struct Closer {
  void operator()(TIFF* t) const { TIFFClose(t); }
};
using File = std::unique_ptr<TIFF, Closer>;

File open(const std::string& path) {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(onError);
    TIFFSetWarningHandler(onWarning);
  });
  last_error.clear();
  File t(TIFFOpen(path.c_str(), "r"));
  if (!t) fail(path, "not a readable TIFF file" + (last_error.empty() ? "" : " (" + last_error + ")"));
  return t;
}

// What a page holds, checked against what Tessera renders.
struct Page {
  uint32_t width = 0, height = 0;
  VoxelType type = VoxelType::UInt8;
  bool bottom_up = false;  // rows stored bottom first (Orientation BOTLEFT)
};

Page pageOf(TIFF* t, const std::string& file, int k, uint64_t file_size) {
  const std::string at = "page " + std::to_string(k + 1);
  Page p;
  uint16_t orientation = ORIENTATION_TOPLEFT;
  TIFFGetField(t, TIFFTAG_ORIENTATION, &orientation);
  if (orientation != ORIENTATION_TOPLEFT && orientation != ORIENTATION_BOTLEFT)
    fail(file, at + " has Orientation " + std::to_string(orientation) +
                   "; Tessera reads pages stored top row first (1) or bottom row first (4), columns left to right");
  p.bottom_up = orientation == ORIENTATION_BOTLEFT;
  // A file cut inside its pixels (its pages listed before them) is found now, not mid-run.
  uint64_t *offsets = nullptr, *counts = nullptr;
  const bool tiled = TIFFIsTiled(t);
  if (TIFFGetField(t, tiled ? TIFFTAG_TILEOFFSETS : TIFFTAG_STRIPOFFSETS, &offsets) &&
      TIFFGetField(t, tiled ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS, &counts) && offsets && counts)
    for (uint32_t i = 0, n = tiled ? TIFFNumberOfTiles(t) : TIFFNumberOfStrips(t); i < n; ++i)
      if (offsets[i] + counts[i] > file_size)
        fail(file, at + "'s " + (tiled ? "tile " : "strip ") + std::to_string(i) + " ends at byte " +
                       std::to_string(offsets[i] + counts[i]) + ", past the file's " + std::to_string(file_size) +
                       " (the file is cut short)");
  uint16_t bits = 1, format = SAMPLEFORMAT_UINT, spp = 1, photometric = PHOTOMETRIC_MINISBLACK, compression = 1;
  TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &p.width);
  TIFFGetField(t, TIFFTAG_IMAGELENGTH, &p.height);
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetField(t, TIFFTAG_PHOTOMETRIC, &photometric);
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &compression);
  if (p.width == 0 || p.height == 0) fail(file, at + " is " + std::to_string(p.width) + " x " + std::to_string(p.height) + " pixels");
  if (spp != 1 || photometric == PHOTOMETRIC_PALETTE || photometric == PHOTOMETRIC_RGB)
    fail(file, at + " is a colour image (" + std::to_string(spp) + " samples a pixel" +
                   (photometric == PHOTOMETRIC_PALETTE ? ", a palette" : "") +
                   "): Tessera renders one value a voxel; save the stack as grayscale (Fiji: Image > Type > 16-bit)");
  if (!TIFFIsCODECConfigured(compression))
    fail(file, at + " uses compression " + std::to_string(compression) + ", which this libtiff cannot decode");
  const bool sign = format == SAMPLEFORMAT_INT, real = format == SAMPLEFORMAT_IEEEFP;
  if (real && bits == 32) p.type = VoxelType::Float32;
  else if (real && bits == 64) p.type = VoxelType::Float64;
  else if (!real && (format == SAMPLEFORMAT_UINT || sign) && (bits == 8 || bits == 16 || bits == 32))
    p.type = bits == 8 ? (sign ? VoxelType::Int8 : VoxelType::UInt8)
             : bits == 16 ? (sign ? VoxelType::Int16 : VoxelType::UInt16)
                          : (sign ? VoxelType::Int32 : VoxelType::UInt32);
  else
    fail(file, at + " has " + std::to_string(bits) + "-bit samples of format " + std::to_string(format) +
                   " (1 unsigned, 2 signed, 3 float): Tessera reads 8, 16 and 32-bit integers and 32 and 64-bit floats");
  return p;
}

// A thumbnail or a pyramid level beside the full-size pages (NewSubfileType bit 0).
bool reduced(TIFF* t) {
  uint32_t kind = 0;
  return TIFFGetField(t, TIFFTAG_SUBFILETYPE, &kind) && (kind & FILETYPE_REDUCEDIMAGE);
}

// The full-size pages of a file, each with where its directory starts. A directory that
// cannot be read (a file cut short) is an error, not the end of the stack.
std::vector<uint64_t> pagesOf(TIFF* t, const std::string& file) {
  std::vector<uint64_t> pages;
  for (int k = 1;; ++k) {
    if (!reduced(t)) pages.push_back(TIFFCurrentDirOffset(t));
    last_error.clear(), last_warning.clear();
    if (TIFFReadDirectory(t)) continue;
    const std::string& why = last_error.empty() ? last_warning : last_error;
    if (!why.empty()) fail(file, "the directory after page " + std::to_string(k) + " cannot be read (" + why + ")");
    return pages;
  }
}

// A name with its digit runs replaced by '#', and those runs: "z012_ch01.tif" -> "z#_ch#.tif",
// {"012", "01"}.
std::string namePattern(const std::string& name, std::vector<std::string>* numbers = nullptr) {
  std::string pattern;
  for (size_t i = 0; i < name.size();) {
    if (!std::isdigit((unsigned char)name[i])) {
      pattern += name[i++];
      continue;
    }
    const size_t start = i;
    while (i < name.size() && std::isdigit((unsigned char)name[i])) ++i;
    pattern += '#';
    if (numbers) numbers->push_back(name.substr(start, i - start));
  }
  return pattern;
}

// A folder's slices: one series numbered by one number, in that number's order (z9 before
// z10). Names of another pattern (a projection saved beside them) or a second number that
// varies (channels, times) are refused.
std::vector<std::string> numberedSlices(const std::string& folder, std::vector<std::string> files) {
  std::sort(files.begin(), files.end());
  auto name = [](const std::string& f) { return fs::path(f).filename().string(); };
  std::vector<std::vector<std::string>> numbers(files.size());
  const std::string pattern = namePattern(name(files[0]), &numbers[0]);
  std::vector<bool> varies(numbers[0].size(), false);
  for (size_t i = 1; i < files.size(); ++i) {
    if (namePattern(name(files[i]), &numbers[i]) != pattern)
      fail(folder, "its TIFF files are not one numbered series: " + name(files[0]) + " and " + name(files[i]) +
                       " differ in more than a number; keep one stack's slices in a folder of their own");
    for (size_t k = 0; k < varies.size(); ++k) varies[k] = varies[k] || numbers[i][k] != numbers[0][k];
  }
  if (std::count(varies.begin(), varies.end(), true) > 1)
    fail(folder, "its TIFF files are numbered by more than one number (" + name(files[0]) + ", " + name(files.back()) +
                     "): several channels or time points? Keep one channel's slices at one time in a folder of their own");
  const size_t k = std::find(varies.begin(), varies.end(), true) - varies.begin();
  if (k == varies.size()) return files;
  // By value: fewer digits once leading zeros are dropped is smaller.
  auto value = [&](size_t i) {
    const std::string& d = numbers[i][k];
    const size_t nz = std::min(d.find_first_not_of('0'), d.size());
    return std::make_pair(d.size() - nz, d.substr(nz));
  };
  std::vector<size_t> order(files.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return value(a) < value(b); });
  std::vector<std::string> sorted;
  for (size_t i : order) sorted.push_back(files[i]);
  return sorted;
}

RawVolumeSpec readStack(const std::string& path) {
  RawVolumeSpec spec;
  spec.format = VolumeFormat::Tiff;
  spec.file = path;
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    for (const auto& e : fs::directory_iterator(path, ec)) {
      const std::string name = e.path().filename().string();
      if (!name.empty() && name[0] != '.' && e.is_regular_file(ec) && isTiffName(name)) files.push_back(e.path().string());
    }
    if (files.empty()) fail(path, "a folder with no .tif or .tiff file");
    files = numberedSlices(path, std::move(files));
  } else {
    files.push_back(path);
  }
  if (files.size() > 65536) fail(path, std::to_string(files.size()) + " TIFF files; at most 65536 slices");
  Page first;
  std::string description;
  float xres = 0, yres = 0;
  for (const std::string& f : files) {
    File t = open(f);
    const uint64_t file_size = (uint64_t)fs::file_size(f, ec);
    if (spec.slices.empty()) {
      char* d = nullptr;
      if (TIFFGetField(t.get(), TIFFTAG_IMAGEDESCRIPTION, &d) && d) description = d;
      TIFFGetField(t.get(), TIFFTAG_XRESOLUTION, &xres);
      TIFFGetField(t.get(), TIFFTAG_YRESOLUTION, &yres);
    }
    const std::vector<uint64_t> pages = pagesOf(t.get(), f);
    if (files.size() > 1 && pages.size() != 1)
      fail(f, "holds " + std::to_string(pages.size()) + " pages; in a folder, each TIFF file is one slice (give a multi-page file itself)");
    for (size_t k = 0; k < pages.size(); ++k) {
      if (!TIFFSetSubDirectory(t.get(), pages[k])) fail(f, "page " + std::to_string(k + 1) + " cannot be read: " + last_error);
      const Page p = pageOf(t.get(), f, (int)k, file_size);
      if (spec.slices.empty()) first = p;
      if (p.width != first.width || p.height != first.height || p.type != first.type)
        fail(f, "page " + std::to_string(k + 1) + " is " + std::to_string(p.width) + " x " + std::to_string(p.height) + " " +
                    voxelTypeName(p.type) + ", the first " + std::to_string(first.width) + " x " + std::to_string(first.height) +
                    " " + voxelTypeName(first.type) + ": a stack's pages are one size and type");
      SliceFile s;
      s.file = f;
      s.offset = pages[k];
      s.bottom_up = p.bottom_up;
      spec.slices.push_back(std::move(s));
    }
    if (spec.slices.size() > 65536) fail(path, "more than 65536 pages; at most 65536 slices");
  }
  if (first.width > 65536 || first.height > 65536) fail(files[0], "pages wider or taller than 65536 pixels");
  spec.dims = {(int)first.width, (int)first.height, (int)spec.slices.size()};
  spec.type = first.type;
  applyTiffMetadata(description, xres, yres, files[0], spec);
  return spec;
}

// A stack's slices by blocks: strips (every column of some rows) or tiles. The file and page
// of the last read stay open, and the blocks of one row of blocks are kept once decoded (a
// window reads a slice row by row, each row across its blocks).
class Blocks : public SliceBytes {
 public:
  explicit Blocks(const RawVolumeSpec& spec)
      : spec_(spec), ts_(voxelTypeSize(spec.type)), width_((size_t)spec.dims[0]), height_((size_t)spec.dims[1]) {}

  void read(size_t z, size_t in, size_t count, unsigned char* dst) override {
    const SliceFile& s = spec_.slices[z];
    select(s, z);
    for (size_t done = 0; done < count;) {
      const size_t at = in + done, row = at / width_, x = at % width_;
      const size_t stored = s.bottom_up ? height_ - 1 - row : row;  // the row's place in the page
      const size_t by = stored / block_h_, bx = x / block_w_;
      const std::vector<unsigned char>& b = block(s, z, by, bx);
      const size_t n = std::min({count - done, width_ - x, (bx + 1) * block_w_ - x});  // to the row's or block's end
      std::memcpy(dst + done * ts_, b.data() + ((stored - by * block_h_) * block_w_ + (x - bx * block_w_)) * ts_, n * ts_);
      done += n;
    }
  }

 private:
  // "f.tif: slice 3": where an error is.
  std::string where(const SliceFile& s, size_t z) const { return s.file + ": slice " + std::to_string(z + 1); }

  void select(const SliceFile& s, size_t z) {
    if (file_ != s.file) {
      file_.clear(), dir_ = UINT64_MAX;
      t_ = open(s.file);
      file_ = s.file;
    }
    if (dir_ == s.offset) return;
    dir_ = UINT64_MAX, block_row_ = SIZE_MAX;
    last_error.clear();
    if (!TIFFSetSubDirectory(t_.get(), s.offset)) throw std::runtime_error(where(s, z) + ": its page cannot be read: " + last_error);
    tiled_ = TIFFIsTiled(t_.get());
    uint16_t compression = COMPRESSION_NONE;
    TIFFGetFieldDefaulted(t_.get(), TIFFTAG_COMPRESSION, &compression);
    compressed_ = compression != COMPRESSION_NONE;
    uint32_t w = 0, h = 0;
    if (tiled_) {
      TIFFGetField(t_.get(), TIFFTAG_TILEWIDTH, &w);
      TIFFGetField(t_.get(), TIFFTAG_TILELENGTH, &h);
      if (w == 0 || h == 0) throw std::runtime_error(where(s, z) + ": a tiled page without its tile size");
      block_w_ = w, block_h_ = h;
    } else {
      TIFFGetFieldDefaulted(t_.get(), TIFFTAG_ROWSPERSTRIP, &h);
      block_w_ = width_, block_h_ = std::clamp<size_t>(h, 1, height_);
    }
    blocks_.assign((width_ + block_w_ - 1) / block_w_, {});
    dir_ = s.offset;
  }

  // Block (by, bx), decoded once per row of blocks.
  const std::vector<unsigned char>& block(const SliceFile& s, size_t z, size_t by, size_t bx) {
    if (by != block_row_) {
      for (auto& b : blocks_) b.clear();
      block_row_ = by;
    }
    std::vector<unsigned char>& b = blocks_[bx];
    if (!b.empty()) return b;
    // A tile is whole even at the page's edge; a strip ends with the page.
    const size_t want = (tiled_ ? block_h_ : std::min(block_h_, height_ - by * block_h_)) * block_w_ * ts_;
    const tmsize_t room = tiled_ ? TIFFTileSize(t_.get()) : TIFFStripSize(t_.get());
    b.resize(std::max<size_t>(want, (size_t)std::max<tmsize_t>(room, 0)));
    last_error.clear();
    const uint32_t index = tiled_ ? TIFFComputeTile(t_.get(), (uint32_t)(bx * block_w_), (uint32_t)(by * block_h_), 0, 0) : (uint32_t)by;
    const tmsize_t got = tiled_ ? TIFFReadEncodedTile(t_.get(), index, b.data(), (tmsize_t)b.size())
                                : TIFFReadEncodedStrip(t_.get(), index, b.data(), (tmsize_t)b.size());
    if (got < (tmsize_t)want) {
      b.clear();
      throw std::runtime_error(where(s, z) + ": " + (tiled_ ? "tile " : "strip ") + std::to_string(index) + " decodes to " +
                               std::to_string(std::max<tmsize_t>(got, 0)) + " bytes, " + std::to_string(want) +
                               " expected (the file is cut short or damaged" + (last_error.empty() ? "" : ": " + last_error) + ")");
    }
    b.resize(want);
    if (compressed_) decoded_bytes += want;  // an uncompressed block is read, not decoded
    return b;
  }

  const RawVolumeSpec& spec_;
  size_t ts_, width_, height_;
  File t_;
  std::string file_;
  uint64_t dir_ = UINT64_MAX;
  bool tiled_ = false, compressed_ = false;
  size_t block_w_ = 1, block_h_ = 1, block_row_ = SIZE_MAX;
  std::vector<std::vector<unsigned char>> blocks_;  // the decoded blocks of row block_row_ (empty: not yet)
};

}  // namespace tiff
}  // namespace

bool isTiffName(const std::string& path) {
  std::string p = std::filesystem::path(path).extension().string();
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  return p == ".tif" || p == ".tiff";
}

RawVolumeSpec readTiffStack(const std::string& path) { return tiff::readStack(path); }

std::unique_ptr<SliceBytes> tiffSliceBytes(const RawVolumeSpec& spec) { return std::make_unique<tiff::Blocks>(spec); }

}  // namespace tessera
