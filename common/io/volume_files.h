// Volume files that describe themselves: NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, `.hdr` +
// `.img`; read with nifticlib), NRRD (`.nrrd` with attached data, `.nhdr` with a data
// file; raw or gzip encoding) and DICOM series (a folder of slices; GDCM). Only the header is read here: the samples are read by the
// same windowed reader as raw files (common/raw_volume.cpp), so a renderer reads only its
// bricks from an uncompressed file. Orientation: Tessera shows index space (i along x,
// j along y, k along z) scaled by the voxel spacing; a NIfTI qform/sform or NRRD space
// directions rotation is not applied, only its spacing.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/volume.h"

namespace tessera {

// The format a file name says: .nii, .nii.gz, .hdr, .img -> Nifti; .nrrd, .nhdr -> Nrrd;
// a folder, .dcm or a file with DICOM's "DICM" at byte 128 -> Dicom; else Raw.
VolumeFormat volumeFormatOf(const std::string& path);
// dims, type, spacing, byte order, data file, offset and compression from the header.
// Throws std::runtime_error naming the file, the field and the value when the header is
// unreadable, inconsistent or describes what Tessera does not render (complex or RGB
// samples; more than one volume unless `time_steps` is given). With `time_steps`, a 4-D file
// (NIfTI dim[4], NRRD's fourth axis) is a time series: its length goes there (1 for 3-D),
// and step t's samples follow step t-1's.
// A DICOM series (a folder of one series, or one file of a folder's series; read with GDCM)
// is a volume of its slices sorted along their normal, evenly spaced, of one shape; each
// slice keeps its file, where its samples start (uncompressed little-endian) and its
// RescaleSlope/Intercept. x runs along a row (columns), y down the rows, z along the normal.
RawVolumeSpec readVolumeHeader(const std::string& path, int* time_steps = nullptr);
// The samples of a DICOM series' slices, as their type's little-endian bytes holding only
// the stored bits (a 12-bit signed sample sign-extended, whatever the bits above held): an
// uncompressed slice by positioned reads of its file (the last one read stays open: windows
// are read slice by slice), a compressed one decoded whole by GDCM (the last one kept).
class DicomSliceBytes {
 public:
  explicit DicomSliceBytes(const RawVolumeSpec& spec);  // spec.slices; kept by reference
  ~DicomSliceBytes();
  DicomSliceBytes(const DicomSliceBytes&) = delete;
  DicomSliceBytes& operator=(const DicomSliceBytes&) = delete;
  // `count` samples of slice z from its sample `in` into dst; errors name the slice's file.
  void read(size_t z, size_t in, size_t count, unsigned char* dst);

 private:
  const RawVolumeSpec& spec_;
  size_t ts_, per_slice_;
  int fd_ = -1;
  size_t open_z_ = SIZE_MAX, decoded_z_ = SIZE_MAX;
  std::vector<unsigned char> decoded_;
};

}  // namespace tessera
