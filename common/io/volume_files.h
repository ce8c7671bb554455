// Volume files that describe themselves: NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, `.hdr` +
// `.img`; read with nifticlib) and NRRD (`.nrrd` with attached data, `.nhdr` with a data
// file; raw or gzip encoding). Only the header is read here: the samples are read by the
// same windowed reader as raw files (common/raw_volume.cpp), so a renderer reads only its
// bricks from an uncompressed file. Orientation: Tessera shows index space (i along x,
// j along y, k along z) scaled by the voxel spacing; a NIfTI qform/sform or NRRD space
// directions rotation is not applied, only its spacing.
#pragma once
#include <string>

#include "common/volume.h"

namespace tessera {

// The format a file name says: .nii, .nii.gz, .hdr, .img -> Nifti; .nrrd, .nhdr -> Nrrd; else Raw.
VolumeFormat volumeFormatOf(const std::string& path);
// dims, type, spacing, byte order, data file, offset and compression from the header.
// Throws std::runtime_error naming the file, the field and the value when the header is
// unreadable, inconsistent or describes what Tessera does not render (more than one
// volume in time, complex or RGB samples).
RawVolumeSpec readVolumeHeader(const std::string& path);

}  // namespace tessera
