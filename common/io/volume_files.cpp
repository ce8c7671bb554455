// Which header reader a volume file needs (see volume_files.h).
#include "common/io/volume_files.h"

#include <algorithm>

namespace tessera {

RawVolumeSpec readNiftiHeader(const std::string& path, int* time_steps);  // nifti_header.cpp
RawVolumeSpec readNrrdHeader(const std::string& path, int* time_steps);   // nrrd_header.cpp

VolumeFormat volumeFormatOf(const std::string& path) {
  std::string p = path;
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  auto ends = [&](const char* e) { const std::string s(e); return p.size() >= s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0; };
  if (ends(".nii") || ends(".nii.gz") || ends(".hdr") || ends(".img") || ends(".hdr.gz") || ends(".img.gz"))
    return VolumeFormat::Nifti;
  if (ends(".nrrd") || ends(".nhdr")) return VolumeFormat::Nrrd;
  return VolumeFormat::Raw;
}

RawVolumeSpec readVolumeHeader(const std::string& path, int* time_steps) {
  return volumeFormatOf(path) == VolumeFormat::Nifti ? readNiftiHeader(path, time_steps)
                                                     : readNrrdHeader(path, time_steps);
}

}  // namespace tessera
