// Volume files that describe themselves: NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, `.hdr` +
// `.img`; read with nifticlib), NRRD (`.nrrd` with attached data, `.nhdr` with a data
// file; raw or gzip encoding), DICOM series (a folder of slices; GDCM) and TIFF stacks (a
// multi-page TIFF or a folder of TIFFs; libtiff). Only the header is read here: the samples are read by the
// same windowed reader as raw files (common/raw_volume.cpp), so a renderer reads only its
// bricks from an uncompressed file. Orientation: Tessera shows index space (i along x,
// j along y, k along z) scaled by the voxel spacing; a NIfTI qform/sform or NRRD space
// directions rotation is not applied, only its spacing.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/volume.h"

namespace tessera {

// The format a file name says: .nii, .nii.gz, .hdr, .img -> Nifti; .nrrd, .nhdr -> Nrrd;
// .tif, .tiff or a folder holding such files -> Tiff; another folder, .dcm or a file with
// DICOM's "DICM" at byte 128 -> Dicom; else Raw.
VolumeFormat volumeFormatOf(const std::string& path);
// A .tif or .tiff name (any case).
bool isTiffName(const std::string& path);
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
// A TIFF stack (a multi-page file, one slice a full-size page; or a folder of single-page
// files in natural name order) is a volume of grayscale pages of one size and sample type;
// ImageJ's metadata gives the spacing (1/resolution across, `spacing=` between slices),
// else it is 1. x runs along a row, y down the rows, z from the first page to the last.
RawVolumeSpec readVolumeHeader(const std::string& path, int* time_steps = nullptr);
// The samples of a volume kept slice by slice (spec.slices: a DICOM series, a TIFF stack), as
// their type's little-endian bytes. A DICOM slice holds only its stored bits (a 12-bit signed
// sample sign-extended, whatever the bits above held): uncompressed, read by positioned reads
// of its file (the last one read stays open: windows are read slice by slice); compressed,
// decoded whole by GDCM (the last one kept). A TIFF slice is read by the strips or tiles that hold the
// samples asked for, decoded by libtiff (the last row of them kept).
class SliceBytes {
 public:
  virtual ~SliceBytes() = default;
  // `count` samples of slice z from its sample `in` into dst; errors name the slice's file.
  virtual void read(size_t z, size_t in, size_t count, unsigned char* dst) = 0;
  uint64_t decoded_bytes = 0;  // what decoders produced (compressed slices, strips, tiles), parts not asked for included
};
// "dims 13 x 11 x 7 x 2 bytes/voxel after a header of 352 bytes need 2354 bytes": what a file
// (or its decompressed stream) of `spec` holds up to the end of time step `step`.
std::string sizeNeeded(const RawVolumeSpec& spec, uint64_t step = 0);
// The reader for spec.format (Dicom or Tiff); spec is kept by reference.
std::unique_ptr<SliceBytes> sliceBytes(const RawVolumeSpec& spec);

}  // namespace tessera
