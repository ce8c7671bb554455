// Writes TIFF pages with libtiff itself, as microscopes' software saves stacks: 16-bit
// grayscale (or colour, to be refused) in strips, optionally LZW, big-endian, bottom row
// first, with ImageJ's or OME's description and a resolution. For the TIFF tests.
#pragma once
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tessera::test::tiff_writer {

// The fields of a page of 16-bit unsigned samples, `samples` a pixel (3: RGB, else grayscale).
inline void pageFields(TIFF* t, uint32_t width, uint32_t height, uint16_t compression, uint16_t samples = 1) {
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, width);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, height);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)16);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_UINT);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, samples);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, samples == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_COMPRESSION, compression);
}

constexpr int kNx = 13, kNy = 11, kNz = 7;

// A different value at every voxel, so any axis mix-up shows.
inline std::vector<uint16_t> samples() {
  std::vector<uint16_t> v((size_t)kNx * kNy * kNz);
  for (int z = 0; z < kNz; ++z)
    for (int y = 0; y < kNy; ++y)
      for (int x = 0; x < kNx; ++x) v[x + kNx * (y + kNy * z)] = (uint16_t)(x * 3 + y * 40 + z * 500 + 100);
  return v;
}

struct PageOptions {
  uint16_t compression = COMPRESSION_NONE;
  uint32_t rows_per_strip = 3;
  uint16_t samples_per_pixel = 1;
  std::string description;
  bool big_endian = false;
  float resolution = 0;  // pixels per unit across (0: not written)
  bool bottom_up = false;  // Orientation BOTLEFT, rows written bottom first
};

// Pages [z0, z1) of samples() into `path`, each one page.
inline void writePages(const std::string& path, int z0, int z1, const PageOptions& o = {}) {
  TIFF* t = TIFFOpen(path.c_str(), o.big_endian ? "wb" : "wl");
  ASSERT_NE(t, nullptr);
  const auto v = samples();
  for (int z = z0; z < z1; ++z) {
    pageFields(t, kNx, kNy, o.compression, o.samples_per_pixel);
    if (o.compression == COMPRESSION_LZW) TIFFSetField(t, TIFFTAG_PREDICTOR, PREDICTOR_HORIZONTAL);
    if (z == z0 && !o.description.empty()) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, o.description.c_str());
    if (o.bottom_up) TIFFSetField(t, TIFFTAG_ORIENTATION, ORIENTATION_BOTLEFT);
    if (o.resolution > 0) {
      TIFFSetField(t, TIFFTAG_XRESOLUTION, o.resolution);
      TIFFSetField(t, TIFFTAG_YRESOLUTION, o.resolution);
      TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
    }
    std::vector<uint16_t> row((size_t)kNx * o.samples_per_pixel);
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, o.rows_per_strip);
    for (int y = 0; y < kNy; ++y) {
      const int vy = o.bottom_up ? kNy - 1 - y : y;  // the volume's row stored as page row y
      for (int x = 0; x < kNx; ++x)
        for (int c = 0; c < o.samples_per_pixel; ++c) row[x * o.samples_per_pixel + c] = v[x + kNx * (vy + kNy * z)];
      ASSERT_EQ(TIFFWriteScanline(t, row.data(), (uint32_t)y, 0), 1);
    }
    ASSERT_EQ(TIFFWriteDirectory(t), 1);
  }
  TIFFClose(t);
}

}  // namespace tessera::test::tiff_writer
