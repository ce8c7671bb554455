// Which header reader a volume file needs (see volume_files.h).
#include "common/io/volume_files.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace tessera {

RawVolumeSpec readNiftiHeader(const std::string& path, int* time_steps);  // nifti_header.cpp
RawVolumeSpec readNrrdHeader(const std::string& path, int* time_steps);   // nrrd_header.cpp
RawVolumeSpec readDicomSeries(const std::string& path);                   // dicom_series.cpp
RawVolumeSpec readTiffStack(const std::string& path);                     // tiff_stack.cpp
std::unique_ptr<SliceBytes> dicomSliceBytes(const RawVolumeSpec& spec);   // dicom_series.cpp
std::unique_ptr<SliceBytes> tiffSliceBytes(const RawVolumeSpec& spec);    // tiff_stack.cpp

VolumeFormat volumeFormatOf(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    // TIFF slices, unless DICOM files are there too (a screenshot saved into a CT export): a
    // few of the other files are looked at for DICOM's marker. Hidden files (macOS's ._x.tif)
    // do not count.
    bool tiff = false;
    int others = 0;
    for (const auto& e : std::filesystem::directory_iterator(path, ec)) {
      const std::string name = e.path().filename().string();
      if (name.empty() || name[0] == '.' || !e.is_regular_file(ec)) continue;
      if (isTiffName(name)) tiff = true;
      else if (others++ < 16 && volumeFormatOf(e.path().string()) == VolumeFormat::Dicom) return VolumeFormat::Dicom;
    }
    return tiff ? VolumeFormat::Tiff : VolumeFormat::Dicom;
  }
  if (isTiffName(path)) return VolumeFormat::Tiff;
  std::string p = path;
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  auto ends = [&](const char* e) { const std::string s(e); return p.size() >= s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0; };
  if (ends(".nii") || ends(".nii.gz") || ends(".hdr") || ends(".hdr.gz")) return VolumeFormat::Nifti;
  // An .img is NIfTI's (or Analyze's) only beside its .hdr: alone it is a raw file by another name.
  if (ends(".img") || ends(".img.gz")) {
    const std::string stem = path.substr(0, path.size() - (ends(".img") ? 4 : 7));
    for (const char* h : {".hdr", ".hdr.gz", ".HDR", ".HDR.GZ"})
      if (std::filesystem::exists(stem + h, ec)) return VolumeFormat::Nifti;
    return VolumeFormat::Raw;
  }
  if (ends(".nrrd") || ends(".nhdr")) return VolumeFormat::Nrrd;
  if (ends(".dcm")) return VolumeFormat::Dicom;
  // DICOM files often have no extension (IM0001): their preamble's "DICM" at byte 128 says it.
  char magic[132] = {};
  if (!std::filesystem::is_regular_file(path, ec)) return VolumeFormat::Raw;  // a FIFO would block
  std::ifstream in(path, std::ios::binary);
  if (in.read(magic, sizeof magic) && std::memcmp(magic + 128, "DICM", 4) == 0) return VolumeFormat::Dicom;
  return VolumeFormat::Raw;
}

RawVolumeSpec readVolumeHeader(const std::string& path, int* time_steps) {
  switch (volumeFormatOf(path)) {
    case VolumeFormat::Nifti: return readNiftiHeader(path, time_steps);
    case VolumeFormat::Dicom: return readDicomSeries(path);  // one step
    case VolumeFormat::Tiff: return readTiffStack(path);     // one step
    default: return readNrrdHeader(path, time_steps);
  }
}

std::unique_ptr<SliceBytes> sliceBytes(const RawVolumeSpec& spec) {
  return spec.format == VolumeFormat::Tiff ? tiffSliceBytes(spec) : dicomSliceBytes(spec);
}

std::string sizeNeeded(const RawVolumeSpec& spec, uint64_t step) {
  const uint64_t ts = voxelTypeSize(spec.type), volume = (uint64_t)spec.dims[0] * spec.dims[1] * spec.dims[2] * ts;
  return "dims " + std::to_string(spec.dims[0]) + " x " + std::to_string(spec.dims[1]) + " x " +
         std::to_string(spec.dims[2]) + " x " + std::to_string(ts) + " bytes/voxel" +
         (spec.offset ? " after a header of " + std::to_string(spec.offset) + " bytes" : "") + " need " +
         std::to_string(spec.offset + (step + 1) * volume) + " bytes" + (step ? " (time step " + std::to_string(step) + ")" : "");
}

}  // namespace tessera
