// A DICOM series as one volume, through GDCM (see volume_files.h): the slices of a folder
// (or of the series one file in it belongs to), sorted along their normal; and their samples.
#include <fcntl.h>
#include <unistd.h>

#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmScanner.h>
#include <gdcmTrace.h>
#include <gdcmTransferSyntax.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/io/volume_files.h"

namespace tessera {
namespace {
namespace dicom {  // a unity build joins this file's helpers with others' (fail, ...)

namespace fs = std::filesystem;

const gdcm::Tag kSeries(0x0020, 0x000e), kDescription(0x0008, 0x103e), kPosition(0x0020, 0x0032),
    kOrientation(0x0020, 0x0037), kRows(0x0028, 0x0010), kColumns(0x0028, 0x0011), kBits(0x0028, 0x0100),
    kSigned(0x0028, 0x0103), kSamples(0x0028, 0x0002), kSlope(0x0028, 0x1053), kIntercept(0x0028, 0x1052),
    kPixelSpacing(0x0028, 0x0030), kFrames(0x0028, 0x0008), kThickness(0x0018, 0x0050), kPixelData(0x7fe0, 0x0010),
    kBitsStored(0x0028, 0x0101), kHighBit(0x0028, 0x0102), kModality(0x0008, 0x0060);

// A multi-valued DICOM string ("0.5\0.5"): its numbers, or none when one does not parse.
std::vector<double> numbers(const char* text) {
  std::vector<double> out;
  if (!text) return out;
  for (const char* p = text; *p;) {
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p || !std::isfinite(x)) return {};
    out.push_back(x);
    p = end;
    while (*p == ' ') ++p;
    if (*p == '\\') ++p;
    else if (*p) return {};
  }
  return out;
}

bool hasDicomMarker(const std::string& file) {
  char head[132] = {};
  std::ifstream in(file, std::ios::binary);
  return in.read(head, sizeof head) && std::memcmp(head + 128, "DICM", 4) == 0;
}

std::string trimmed(const char* text) {
  std::string s = text ? text : "";
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  return s;
}

struct Slice {
  std::string file;
  double along = 0;  // position along the normal, mm
  Vec3 position{0, 0, 0};
  double slope = 1, inter = 0;
};

[[noreturn]] void fail(const std::string& where, const std::string& what) { throw std::runtime_error(where + ": " + what); }

// Where slice `file`'s samples start, or 0 when GDCM must decode them: anything but
// uncompressed little-endian (an encapsulated, deflated or big-endian transfer syntax).
// GDCM stops after the pixel data element's header without reading its value.
uint64_t samplesOffset(const std::string& file, uint64_t bytes) {
  gdcm::Reader r;
  r.SetFileName(file.c_str());
  if (!r.ReadUpToTag(kPixelData, {kPixelData})) fail(file, "GDCM cannot read its header");
  const gdcm::TransferSyntax ts = r.GetFile().GetHeader().GetDataSetTransferSyntax();
  const bool implicit = ts == gdcm::TransferSyntax::ImplicitVRLittleEndian;
  if (!implicit && ts != gdcm::TransferSyntax::ExplicitVRLittleEndian) return 0;
  const uint64_t at = r.GetStreamCurrentPosition(), header = implicit ? 8 : 12;
  // Checked, as the offset is where GDCM stopped: the element's tag and length before it.
  unsigned char h[12] = {};
  std::ifstream in(file, std::ios::binary);
  if (at < header || !in.seekg((std::streamoff)(at - header)) || !in.read(reinterpret_cast<char*>(h), (std::streamsize)header) ||
      !(h[0] == 0xe0 && h[1] == 0x7f && h[2] == 0x10 && h[3] == 0x00))
    fail(file, "no pixel data (7FE0,0010) where GDCM found it");
  const unsigned char* len = h + header - 4;
  const uint64_t length = len[0] | len[1] << 8 | len[2] << 16 | (uint64_t)len[3] << 24;
  if (length == 0xffffffffu) return 0;  // encapsulated after all: decode
  if (length < bytes)
    fail(file, "pixel data holds " + std::to_string(length) + " bytes but rows x columns x bits need " +
                   std::to_string(bytes));
  return at;
}

// The files of the series `chosen` belongs to, or of the one series in `folder`.
std::vector<std::string> seriesFiles(const gdcm::Scanner& sc, const std::vector<std::string>& images,
                                     const std::string& folder, const std::string& chosen) {
  std::map<std::string, std::vector<std::string>> by_series;
  for (const std::string& f : images) by_series[trimmed(sc.GetValue(f.c_str(), kSeries))].push_back(f);
  if (!chosen.empty()) return by_series[trimmed(sc.GetValue(chosen.c_str(), kSeries))];
  if (by_series.size() == 1) return by_series.begin()->second;
  std::string list;
  for (const auto& [uid, files] : by_series)
    list += "\n  " + std::to_string(files.size()) + " slices, '" + trimmed(sc.GetValue(files[0].c_str(), kDescription)) +
            "' (series " + uid + "), e.g. " + fs::path(files[0]).lexically_relative(folder).string();
  fail(folder, "holds " + std::to_string(by_series.size()) +
                   " series; name one file of the one to show (volume: {file: " + fs::path(folder).filename().string() +
                   "/<that file>}):" + list);
}

RawVolumeSpec readSeries(const std::string& path) {
  gdcm::Trace::SetWarning(false);  // GDCM's own warnings go to stderr; ours name the file and tag
  std::error_code ec;
  const bool is_folder = fs::is_directory(path, ec);
  std::string folder = is_folder ? path : fs::path(path).parent_path().string();
  if (folder.empty()) folder = ".";
  gdcm::Scanner sc;
  for (const gdcm::Tag& t : {kSeries, kDescription, kPosition, kOrientation, kRows, kColumns, kBits, kSigned, kSamples,
                             kSlope, kIntercept, kPixelSpacing, kFrames, kThickness, kBitsStored, kHighBit, kModality})
    sc.AddTag(t);
  // The folder's files; none an image (a CD's DICOMDIR beside a DICOM/ tree): its sub-folders'.
  std::vector<std::string> files, images;  // images: DICOM files with an image (not a DICOMDIR, not a report)
  for (bool deep : {false, true}) {
    if (deep && (!is_folder || !images.empty())) break;
    files.clear();
    // Only files with DICOM's marker go to GDCM (a big raw file beside the series is not parsed).
    auto add = [&](const fs::directory_entry& e) {
      if (e.is_regular_file(ec) && hasDicomMarker(e.path().string())) files.push_back(e.path().string());
    };
    if (!deep) {
      for (const auto& e : fs::directory_iterator(folder, ec)) add(e);
    } else {  // an export's tree is a few levels deep; a folder that is not one is not scanned whole
      for (auto it = fs::recursive_directory_iterator(folder, ec); !ec && it != fs::recursive_directory_iterator();
           it.increment(ec)) {
        if (it.depth() >= 4) it.disable_recursion_pending();
        add(*it);
        if (files.size() > 100000) fail(folder, "more than 100000 files under it: name the series' own folder");
      }
    }
    if (ec) fail(folder, "cannot list the folder: " + ec.message());
    std::sort(files.begin(), files.end());
    sc.Scan(files);
    for (const std::string& f : files)
      if (sc.IsKey(f.c_str()) && sc.GetValue(f.c_str(), kRows)) images.push_back(f);
  }
  std::string chosen;  // the file named, as the folder's listing spells it
  for (const std::string& f : images)
    if (!is_folder && fs::path(f).filename() == fs::path(path).filename()) chosen = f;
  if (!is_folder && chosen.empty()) fail(path, "not a DICOM file with an image (GDCM cannot read it, or it has no Rows)");
  if (images.empty())
    fail(folder, "no DICOM image in it or its sub-folders (" + std::to_string(files.size()) +
                     " files with DICOM's marker, none an image)");
  const std::vector<std::string> series = seriesFiles(sc, images, folder, chosen);

  // Every slice must share the first one's shape, samples and orientation.
  const std::string& first = series[0];
  auto value = [&](const std::string& f, const gdcm::Tag& t) { return trimmed(sc.GetValue(f.c_str(), t)); };
  const std::vector<double> orientation = numbers(sc.GetValue(first.c_str(), kOrientation));
  const std::vector<double> pixel = numbers(sc.GetValue(first.c_str(), kPixelSpacing));
  const int rows = std::atoi(value(first, kRows).c_str()), columns = std::atoi(value(first, kColumns).c_str());
  const int bits = std::atoi(value(first, kBits).c_str());
  const bool is_signed = value(first, kSigned) == "1";
  if (rows <= 0 || columns <= 0 || rows > 65536 || columns > 65536)
    fail(first, "Rows " + value(first, kRows) + ", Columns " + value(first, kColumns) + ": expected 1..65536 each");
  if (const std::string s = value(first, kSamples); !s.empty() && s != "1")
    fail(first, "SamplesPerPixel " + s + ": a colour image; Tessera renders one value a voxel");
  if (const std::string n = value(first, kFrames); !n.empty() && std::atoi(n.c_str()) > 1)
    fail(first, "a multi-frame image (NumberOfFrames " + n + "); Tessera reads a series of one-frame files");
  if (bits != 8 && bits != 16 && bits != 32) fail(first, "BitsAllocated " + value(first, kBits) + ": expected 8, 16 or 32");
  // The stored bits sit at the bottom (HighBit = BitsStored - 1); the bits above are not the
  // value's (a 12-bit signed sample need not be sign-extended in its 16 bits).
  const int stored_bits = value(first, kBitsStored).empty() ? bits : std::atoi(value(first, kBitsStored).c_str());
  if (stored_bits < 1 || stored_bits > bits) fail(first, "BitsStored " + value(first, kBitsStored) + " of " + value(first, kBits));
  if (!value(first, kHighBit).empty() && std::atoi(value(first, kHighBit).c_str()) != stored_bits - 1)
    fail(first, "HighBit " + value(first, kHighBit) + " with BitsStored " + std::to_string(stored_bits) +
                    ": only samples stored at the bottom bits are read");
  const VoxelType type = bits == 8 ? (is_signed ? VoxelType::Int8 : VoxelType::UInt8)
                         : bits == 16 ? (is_signed ? VoxelType::Int16 : VoxelType::UInt16)
                                      : (is_signed ? VoxelType::Int32 : VoxelType::UInt32);
  if (orientation.size() != 6 && series.size() > 1)
    fail(first, "no ImageOrientationPatient (0020,0037): the slices cannot be put in order");
  const Vec3 row{orientation.size() == 6 ? orientation[0] : 1, orientation.size() == 6 ? orientation[1] : 0,
                 orientation.size() == 6 ? orientation[2] : 0};
  const Vec3 col{orientation.size() == 6 ? orientation[3] : 0, orientation.size() == 6 ? orientation[4] : 1,
                 orientation.size() == 6 ? orientation[5] : 0};
  const Vec3 normal = cross(row, col);
  std::vector<Slice> slices;
  for (const std::string& f : series) {
    for (const gdcm::Tag& t : {kRows, kColumns, kBits, kSigned, kPixelSpacing, kBitsStored})
      if (value(f, t) != value(first, t))
        fail(f, "tag (" + gdcm::Tag(t).PrintAsContinuousString() + ") is '" + value(f, t) + "' but '" + value(first, t) +
                    "' in " + fs::path(first).filename().string() + ": one series must have one shape");
    const std::vector<double> o = numbers(sc.GetValue(f.c_str(), kOrientation));
    for (size_t i = 0; i < o.size() && i < orientation.size(); ++i)
      if (std::abs(o[i] - orientation[i]) > 1e-4) fail(f, "its orientation differs from " + fs::path(first).filename().string() + "'s");
    const std::vector<double> p = numbers(sc.GetValue(f.c_str(), kPosition));
    if (p.size() != 3 && series.size() > 1) fail(f, "no ImagePositionPatient (0020,0032): the slices cannot be put in order");
    Slice s{f, p.size() == 3 ? dot(Vec3{p[0], p[1], p[2]}, normal) : 0};
    if (p.size() == 3) s.position = {p[0], p[1], p[2]};
    if (const auto m = numbers(sc.GetValue(f.c_str(), kSlope)); m.size() == 1) s.slope = m[0];
    if (const auto b = numbers(sc.GetValue(f.c_str(), kIntercept)); b.size() == 1) s.inter = b[0];
    slices.push_back(s);
  }
  std::sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) { return a.along < b.along; });

  // Evenly spaced, as a volume's slices are (a missing file shows as a gap twice as wide).
  double dz = 1;
  if (slices.size() > 1) {
    dz = (slices.back().along - slices.front().along) / (double)(slices.size() - 1);
    for (size_t k = 1; k < slices.size(); ++k) {
      const double gap = slices[k].along - slices[k - 1].along;
      if (!(gap > 0))
        fail(fs::path(slices[k].file).filename().string(), "lies where " + fs::path(slices[k - 1].file).filename().string() +
                                                               " lies (two acquisitions in one series?)");
      if (std::abs(gap - dz) > 0.01 * dz + 1e-6)
        fail(folder, "slices are not evenly spaced: " + fs::path(slices[k - 1].file).filename().string() + " to " +
                         fs::path(slices[k].file).filename().string() + " is " + std::to_string(gap) + " mm, " +
                         std::to_string(dz) + " mm on average (a missing slice?)");
    }
  } else if (const auto t = numbers(sc.GetValue(first.c_str(), kThickness)); t.size() == 1 && t[0] > 0) {
    dz = t[0];
  }
  RawVolumeSpec spec;
  // Slices that shift in their own plane from one to the next (a CT gantry tilt) are drawn
  // stacked straight: the volume is sheared by this angle, which a warning names.
  if (slices.size() > 1) {
    const Vec3 d = slices.back().position - slices.front().position;
    const Vec3 in_plane = d - normal * dot(d, normal);
    spec.dicom_tilt_degrees = std::atan2(length(in_plane), dot(d, normal)) * 180 / std::numbers::pi;
    if (std::abs(spec.dicom_tilt_degrees) > 0.01) {
      char b[300];
      std::snprintf(b, sizeof b,
                    "the DICOM slices shift in their own plane from one to the next (a gantry tilt of %.3g degrees); "
                    "Tessera stacks them straight, so the volume is drawn sheared by that angle",
                    spec.dicom_tilt_degrees);
      spec.notes.push_back(b);
    }
  }
  // DICOM's patient axes (LPS: +x left, +y posterior, +z superior) along the volume's x (a
  // row), y (down the rows) and z (the normal): where the default camera puts the front.
  // A single slice without ImageOrientationPatient has no patient axes: left at 0 (seen as
  // an image is).
  if (orientation.size() == 6) spec.anterior = {-row.y, -col.y, -normal.y}, spec.superior = {row.z, col.z, normal.z};
  spec.modality = value(first, kModality);
  spec.format = VolumeFormat::Dicom;
  spec.file = path;
  spec.dims = {columns, rows, (int)slices.size()};
  spec.type = type;
  // PixelSpacing is (between rows, between columns): y first.
  spec.spacing = {pixel.size() == 2 ? pixel[1] : 1, pixel.size() == 2 ? pixel[0] : 1, dz};
  if (slices.size() > 65536) fail(folder, std::to_string(slices.size()) + " slices: at most 65536");
  const uint64_t bytes = (uint64_t)rows * columns * (bits / 8);
  for (const Slice& s : slices) {
    const uint64_t at = samplesOffset(s.file, bytes);
    spec.slices.push_back(SliceFile{s.file, at, at == 0, s.slope, s.inter, stored_bits});
  }
  return spec;
}

std::vector<unsigned char> decodeSlice(const std::string& file, uint64_t bytes, int bits) {
  gdcm::ImageReader r;
  r.SetFileName(file.c_str());
  if (!r.Read()) fail(file, "GDCM cannot read it as an image");
  const gdcm::Image& image = r.GetImage();
  // The layout the headers promised (a decoder could hand back another).
  if (image.GetPixelFormat().GetBitsAllocated() != bits || image.GetPixelFormat().GetSamplesPerPixel() != 1 ||
      image.GetBufferLength() != bytes)
    fail(file, "GDCM decodes it to " + std::to_string(image.GetPixelFormat().GetBitsAllocated()) + "-bit samples, " +
                   std::to_string(image.GetBufferLength()) + " bytes, where the header says " + std::to_string(bits) +
                   "-bit, " + std::to_string(bytes) + " bytes");
  std::vector<unsigned char> out(image.GetBufferLength());
  if (!image.GetBuffer(reinterpret_cast<char*>(out.data())))
    fail(file, std::string("GDCM cannot decode its pixel data (transfer syntax ") +
                   gdcm::TransferSyntax::GetTSString(image.GetTransferSyntax()) + ")");
  return out;
}

}  // namespace dicom
}  // namespace

namespace {
namespace dicom {
class SliceFiles : public SliceBytes {
 public:
  explicit SliceFiles(const RawVolumeSpec& spec)
      : spec_(spec), ts_(voxelTypeSize(spec.type)), per_slice_((size_t)spec.dims[0] * spec.dims[1]) {}
  ~SliceFiles() override {
    if (fd_ >= 0) ::close(fd_);
  }
  SliceFiles(const SliceFiles&) = delete;
  SliceFiles& operator=(const SliceFiles&) = delete;
  void read(size_t z, size_t in, size_t count, unsigned char* dst) override;

 private:
  const RawVolumeSpec& spec_;
  size_t ts_, per_slice_;
  int fd_ = -1;
  size_t open_z_ = SIZE_MAX, decoded_z_ = SIZE_MAX;
  std::vector<unsigned char> decoded_;
};
}  // namespace dicom
}  // namespace

RawVolumeSpec readDicomSeries(const std::string& path) { return dicom::readSeries(path); }

std::unique_ptr<SliceBytes> dicomSliceBytes(const RawVolumeSpec& spec) { return std::make_unique<dicom::SliceFiles>(spec); }

void dicom::SliceFiles::read(size_t z, size_t in, size_t count, unsigned char* dst) {
  const SliceFile& s = spec_.slices[z];
  if (s.encoded) {
    if (decoded_z_ != z)
      decoded_z_ = SIZE_MAX, decoded_ = dicom::decodeSlice(s.file, per_slice_ * ts_, (int)ts_ * 8), decoded_z_ = z,
      decoded_bytes += decoded_.size();
    std::memcpy(dst, decoded_.data() + in * ts_, count * ts_);
  } else {
    if (open_z_ != z) {
      if (fd_ >= 0) ::close(fd_);
      open_z_ = SIZE_MAX;
      fd_ = ::open(s.file.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd_ < 0) dicom::fail(s.file, std::string("cannot open: ") + std::strerror(errno));
      open_z_ = z;
    }
    for (size_t done = 0; done < count * ts_;) {
      const ssize_t r = ::pread(fd_, dst + done, count * ts_ - done, (off_t)(s.offset + in * ts_ + done));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) dicom::fail(s.file, r < 0 ? std::string("read failed: ") + std::strerror(errno) : "read failed: file shrank");
      done += (size_t)r;
    }
  }
  // Only the stored bits: the bits above cleared, or copies of the sign bit for a signed type
  // (what GDCM's decoder gives; uncompressed bytes may hold anything there, an overlay's bits).
  const int bits = s.bits_stored;
  if (bits <= 0 || bits >= (int)ts_ * 8) return;
  const bool is_signed = spec_.type == VoxelType::Int8 || spec_.type == VoxelType::Int16 || spec_.type == VoxelType::Int32;
  const uint32_t low = (1u << bits) - 1, sign = 1u << (bits - 1);  // bits < the type's, so < 32
  for (size_t i = 0; i < count; ++i) {
    uint32_t v = 0;
    std::memcpy(&v, dst + i * ts_, ts_);  // little-endian: the sample's bytes are v's low ones
    v &= low;
    if (is_signed && (v & sign)) v |= ~low;
    std::memcpy(dst + i * ts_, &v, ts_);
  }
}

}  // namespace tessera
