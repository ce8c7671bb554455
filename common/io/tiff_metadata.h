// The metadata of a TIFF stack's first page (its ImageDescription): ImageJ's or OME-TIFF's
// axes and spacing.
#pragma once
#include <string>

#include "common/volume.h"

namespace tessera {

// Sets spec.spacing where the description gives it (ImageJ: 1/xres, 1/yres across a page
// and `spacing=` between pages; OME: PhysicalSizeX/Y/Z); an axis neither gives is 1, with
// spec.spacing_known false there (a warning says so). Adds a note
// when ImageJ's pages are called channels or time points with no other axis (read as z).
// Throws naming `file` for several channels or time points, and for a file ImageJ wrote with
// more images than spec.slices holds pages.
void applyTiffMetadata(const std::string& description, float xres, float yres, const std::string& file, RawVolumeSpec& spec);

}  // namespace tessera
