// Volume files that describe themselves: NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, `.hdr` +
// `.img`; read with nifticlib), NRRD (`.nrrd` with attached data, `.nhdr` with a data
// file; raw or gzip encoding) and DICOM series (a folder of slices; GDCM). Only the header is read here: the samples are read by the
// same windowed reader as raw files (common/raw_volume.cpp), so a renderer reads only its
// bricks from an uncompressed file. Orientation: Tessera shows index space (i along x,
// j along y, k along z) scaled by the voxel spacing; a NIfTI qform/sform or NRRD space
// directions rotation is not applied, only its spacing.
#pragma once
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
// A compressed (or big-endian) DICOM slice's samples, decoded by GDCM: `bytes` of `bits`-bit
// samples, or an error naming the file.
std::vector<unsigned char> decodeDicomSlice(const std::string& file, uint64_t bytes, int bits);

}  // namespace tessera
