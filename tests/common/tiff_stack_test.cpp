// TIFF stacks, written with libtiff itself: a multi-page file (strips, LZW with a predictor,
// uncompressed) and a folder of single-page files load as the raw file of the same samples,
// window by window; ImageJ's spacing is read; what Tessera cannot render is named.
#include <gtest/gtest.h>
#include <tiffio.h>

#include <algorithm>
#include <filesystem>
#include <regex>
#include <fstream>
#include <string>
#include <vector>

#include "common/io/volume_files.h"
#include "common/scene.h"
#include "tests/common/load_error.h"
#include "tests/common/raw_spec.h"
#include "tests/common/temp_dir.h"
#include "tests/common/tiff_writer.h"

namespace tessera {
namespace {
namespace tiff_test {  // a unity build joins test files: volume_files_test.cpp has samples() too

using test::TempDir;

// Declared here, not by a using-directive: those names would sit in `tessera`, behind the
// unity build's other samples().
using test::tiff_writer::kNx, test::tiff_writer::kNy, test::tiff_writer::kNz, test::tiff_writer::samples,
    test::tiff_writer::PageOptions, test::tiff_writer::writePages;

Volume reference(const TempDir& t, std::array<double, 3> spacing = {1, 1, 1}) {
  const auto v = samples();
  return loadRawVolume(test::rawSpec(t.write("ref.raw", v.data(), v.size() * 2), {kNx, kNy, kNz}, VoxelType::UInt16,
                                     spacing, false, {0, 0}));
}

using test::loadError;

void expectWindowsMatch(const Scene& s, const Volume& whole) {
  VolumeReader reader(s);
  for (const VoxelBox& box : {VoxelBox{{0, 0, 0}, {kNx, kNy, 3}}, VoxelBox{{2, 4, 2}, {9, 10, 7}}, VoxelBox{{0, 5, 6}, {kNx, 6, 7}}}) {
    const Volume w = reader.read(box);
    ASSERT_EQ(w.dims, (std::array<int, 3>{box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]}));
    for (int z = 0; z < w.dims[2]; ++z)
      for (int y = 0; y < w.dims[1]; ++y)
        for (int x = 0; x < w.dims[0]; ++x)
          ASSERT_EQ(w.at(x, y, z), whole.at(x + box.lo[0], y + box.lo[1], z + box.lo[2])) << x << " " << y << " " << z;
  }
}

TEST(TiffStack, AMultiPageFileLoadsAsTheRawFileWindowByWindow) {
  TempDir t("tiff-pages");
  const Volume ref = reference(t);
  auto options = [](uint16_t compression, uint32_t rows_per_strip, bool big_endian) {
    PageOptions o;
    o.compression = compression, o.rows_per_strip = rows_per_strip, o.big_endian = big_endian;
    return o;
  };
  // Strips of 3 rows; LZW with a predictor, 4 rows; one strip a page; big-endian deflate, 1 row.
  for (const PageOptions& o : {options(COMPRESSION_NONE, 3, false), options(COMPRESSION_LZW, 4, false),
                               options(COMPRESSION_NONE, 100, false), options(COMPRESSION_ADOBE_DEFLATE, 1, true)}) {
    writePages(t.file("stack.tif"), 0, kNz, o);
    const Scene s = parseScene("volume: {file: stack.tif}\n", t.path.string(), "s.yaml");
    const Volume v = loadVolume(s);
    EXPECT_EQ(v.dims, ref.dims);
    EXPECT_EQ(v.data_range, ref.data_range);
    EXPECT_EQ(v.values, ref.values) << "compression " << o.compression << ", rows per strip " << o.rows_per_strip;
    expectWindowsMatch(s, v);
  }
}

TEST(TiffStack, AFolderOfPagesIsReadInNaturalNameOrder) {
  TempDir t("tiff-folder");
  std::filesystem::create_directories(t.path / "slices");
  for (int z = 0; z < kNz; ++z) writePages((t.path / "slices" / ("slice" + std::to_string(z + 8) + ".tif")).string(), z, z + 1);
  std::filesystem::create_directories(t.path / "slices" / "notes");  // other entries are left alone
  EXPECT_EQ(volumeFormatOf((t.path / "slices").string()), VolumeFormat::Tiff);
  const Scene s = parseScene("volume: {file: slices}\n", t.path.string(), "s.yaml");
  const Volume v = loadVolume(s);
  const Volume ref = reference(t);
  EXPECT_EQ(v.values, ref.values) << "slice8..slice14: slice10 sorts after slice9";
  expectWindowsMatch(s, v);
}

TEST(TiffStack, ImageJsSpacingIsRead) {
  TempDir t("tiff-imagej");
  PageOptions o;
  o.description = "ImageJ=1.54f\nimages=7\nslices=7\nunit=micron\nspacing=2.5\nloop=false\n";
  o.resolution = 4;  // pixels per micron: 0.25 micron across
  writePages(t.file("ij.tif"), 0, kNz, o);
  const Volume v = loadVolume(parseScene("volume: {file: ij.tif}\n", t.path.string(), "s.yaml"));
  EXPECT_EQ(v.spacing, (std::array<double, 3>{0.25, 0.25, 2.5}));
  EXPECT_EQ(v.values, reference(t).values);
  // The scene's spacing replaces it; without ImageJ's metadata the spacing is 1.
  EXPECT_EQ(loadVolume(parseScene("volume: {file: ij.tif, spacing: [1, 2, 3]}\n", t.path.string(), "s.yaml")).spacing,
            (std::array<double, 3>{1, 2, 3}));
  writePages(t.file("plain.tif"), 0, kNz);
  EXPECT_EQ(loadVolume(parseScene("volume: {file: plain.tif}\n", t.path.string(), "s.yaml")).spacing,
            (std::array<double, 3>{1, 1, 1}));
}

TEST(TiffStack, WhatTesseraCannotRenderIsNamed) {
  TempDir t("tiff-bad");
  auto expectSays = [&](const std::string& file, const std::string& what) {
    const std::string e = loadError("volume: {file: " + file + "}\n", t.path.string());
    EXPECT_NE(e.find(what), std::string::npos) << "expected: " << what << "\ngot: " << e;
  };
  PageOptions rgb;
  rgb.samples_per_pixel = 3;
  writePages(t.file("rgb.tif"), 0, 2, rgb);
  expectSays("rgb.tif", "rgb.tif: page 1 is a colour image (3 samples a pixel)");
  PageOptions channels;
  channels.description = "ImageJ=1.54f\nimages=6\nchannels=2\nslices=3\nhyperstack=true\n";
  writePages(t.file("two.tif"), 0, 6, channels);
  expectSays("two.tif", "two.tif: an ImageJ hyperstack of 2 channels");
  std::ofstream(t.file("text.tif")) << "not a TIFF";
  expectSays("text.tif", "text.tif: not a readable TIFF file");
  // A page of another size in a folder, and a file cut short in its last strips.
  std::filesystem::create_directories(t.path / "mixed");
  writePages((t.path / "mixed" / "a1.tif").string(), 0, 1);
  writePages((t.path / "mixed" / "a2.tif").string(), 0, 2);
  expectSays("mixed", "a2.tif: holds 2 pages; in a folder, each TIFF file is one slice");
  writePages(t.file("cut.tif"), 0, kNz);
  std::filesystem::resize_file(t.file("cut.tif"), std::filesystem::file_size(t.file("cut.tif")) - 600);
  const std::string cut = loadError("volume: {file: cut.tif}\n", t.path.string());
  EXPECT_NE(cut.find("cut.tif"), std::string::npos) << cut;
  EXPECT_NE(cut.find("cannot be read"), std::string::npos) << cut;  // not a stack of fewer pages
}

// Tiles (large microscope planes, OME-TIFF): 40 x 36 pages in 16 x 16 tiles, the last column
// and row of tiles partly outside the page.
TEST(TiffStack, TiledPagesLoadAsTheRawFileWindowByWindow) {
  TempDir t("tiff-tiles");
  constexpr int w = 40, h = 36, d = 5, tile = 16;
  auto value = [](int x, int y, int z) { return (uint16_t)(x * 7 + y * 300 + z * 11000); };
  TIFF* f = TIFFOpen(t.file("tiles.tif").c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::vector<uint16_t> raw;
  for (int z = 0; z < d; ++z) {
    test::tiff_writer::pageFields(f, w, h, COMPRESSION_LZW);
    TIFFSetField(f, TIFFTAG_TILEWIDTH, (uint32_t)tile);
    TIFFSetField(f, TIFFTAG_TILELENGTH, (uint32_t)tile);
    for (int ty = 0; ty < h; ty += tile)
      for (int tx = 0; tx < w; tx += tile) {
        std::vector<uint16_t> b(tile * tile, 0);
        for (int y = ty; y < std::min(h, ty + tile); ++y)
          for (int x = tx; x < std::min(w, tx + tile); ++x) b[(y - ty) * tile + (x - tx)] = value(x, y, z);
        ASSERT_GE(TIFFWriteTile(f, b.data(), (uint32_t)tx, (uint32_t)ty, 0, 0), 0);
      }
    ASSERT_EQ(TIFFWriteDirectory(f), 1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) raw.push_back(value(x, y, z));
  }
  TIFFClose(f);
  const Scene s = parseScene("volume: {file: tiles.tif}\n", t.path.string(), "s.yaml");
  const Volume v = loadVolume(s);
  const Volume want = loadRawVolume(test::rawSpec(t.write("tiles.raw", raw.data(), raw.size() * 2), {w, h, d},
                                                  VoxelType::UInt16, {1, 1, 1}, false, {0, 0}));
  EXPECT_EQ(v.values, want.values);
  VolumeReader reader(s);
  for (const VoxelBox& box : {VoxelBox{{0, 0, 0}, {w, 17, 2}}, VoxelBox{{5, 14, 1}, {37, 33, 5}}, VoxelBox{{33, 30, 4}, {40, 36, 5}}}) {
    const Volume part = reader.read(box);
    for (int z = box.lo[2]; z < box.hi[2]; ++z)
      for (int y = box.lo[1]; y < box.hi[1]; ++y)
        for (int x = box.lo[0]; x < box.hi[0]; ++x)
          ASSERT_EQ(part.at(x - box.lo[0], y - box.lo[1], z - box.lo[2]), v.at(x, y, z)) << x << " " << y << " " << z;
  }
}

TEST(TiffStack, PagesStoredBottomRowFirstAreTurnedUpright) {
  TempDir t("tiff-botleft");
  PageOptions o;
  o.bottom_up = true;
  o.rows_per_strip = 4;
  writePages(t.file("up.tif"), 0, kNz, o);
  const Scene s = parseScene("volume: {file: up.tif}\n", t.path.string(), "s.yaml");
  const Volume v = loadVolume(s);
  EXPECT_EQ(v.values, reference(t).values);
  expectWindowsMatch(s, v);
}

TEST(TiffStack, FloatPagesKeepTheirValues) {
  TempDir t("tiff-float");
  const std::vector<float> v{-1.5f, 0.25f, 3.0f, 7.75f, 2.0f, -0.5f, 1.0f, 4.5f};  // 2 x 2 x 2
  TIFF* f = TIFFOpen(t.file("f.tif").c_str(), "w");
  ASSERT_NE(f, nullptr);
  for (int z = 0; z < 2; ++z) {
    TIFFSetField(f, TIFFTAG_IMAGEWIDTH, (uint32_t)2);
    TIFFSetField(f, TIFFTAG_IMAGELENGTH, (uint32_t)2);
    TIFFSetField(f, TIFFTAG_BITSPERSAMPLE, (uint16_t)32);
    TIFFSetField(f, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_IEEEFP);
    TIFFSetField(f, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
    TIFFSetField(f, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    for (int y = 0; y < 2; ++y) ASSERT_EQ(TIFFWriteScanline(f, const_cast<float*>(v.data() + 4 * z + 2 * y), (uint32_t)y, 0), 1);
    ASSERT_EQ(TIFFWriteDirectory(f), 1);
  }
  TIFFClose(f);
  const Volume got = loadVolume(parseScene("volume: {file: f.tif}\n", t.path.string(), "s.yaml"));
  const Volume want = loadRawVolume(test::rawSpec(t.write("f.raw", v.data(), v.size() * 4), {2, 2, 2}, VoxelType::Float32,
                                                  {1, 1, 1}, false, {0, 0}));
  EXPECT_EQ(got.data_range, (std::array<double, 2>{-1.5, 7.75}));
  EXPECT_EQ(got.values, want.values);
}

// Found by review: a screenshot saved into a DICOM export made the folder a TIFF stack; a
// projection or a second channel in a folder of slices became slices; OME-TIFF's channels
// became slices; macOS's ._ files were read as slices.
TEST(TiffStack, AFolderIsOneNumberedSeriesOfOneChannel) {
  TempDir t("tiff-folders");
  const auto folder = [&](const std::string& name) {
    std::filesystem::create_directories(t.path / name);
    return t.path / name;
  };
  auto expectSays = [&](const std::string& file, const std::string& what) {
    const std::string e = loadError("volume: {file: " + file + "}\n", t.path.string());
    EXPECT_NE(e.find(what), std::string::npos) << "expected: " << what << "\ngot: " << e;
  };
  const auto ct = folder("ct");
  std::string dicom(132, '\0');
  dicom.replace(128, 4, "DICM");
  std::ofstream(ct / "IM0001", std::ios::binary) << dicom;
  writePages((ct / "screenshot.tif").string(), 0, 1);
  EXPECT_EQ(volumeFormatOf(ct.string()), VolumeFormat::Dicom);

  const auto stack = folder("stack");
  for (int z = 0; z < kNz; ++z) writePages((stack / ("cell_z" + std::to_string(z) + ".tif")).string(), z, z + 1);
  std::ofstream(stack / "._cell_z0.tif") << "macOS resource fork";
  EXPECT_EQ(loadVolume(parseScene("volume: {file: stack}\n", t.path.string(), "s.yaml")).values, reference(t).values);
  writePages((stack / "MAX_cell.tif").string(), 0, 1);
  expectSays("stack", "its TIFF files are not one numbered series: MAX_cell.tif and cell_z0.tif differ in more than a number");

  const auto channels = folder("channels");
  for (int z = 0; z < 2; ++z)
    for (int c = 0; c < 2; ++c)
      writePages((channels / ("cell_z" + std::to_string(z) + "_ch" + std::to_string(c) + ".tif")).string(), z, z + 1);
  expectSays("channels", "its TIFF files are numbered by more than one number");

  PageOptions ome;
  ome.description = "<?xml version=\"1.0\"?><OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\"><Image ID=\"Image:0\">"
                    "<Pixels ID=\"Pixels:0\" DimensionOrder=\"XYCZT\" Type=\"uint16\" SizeX=\"13\" SizeY=\"11\" SizeZ=\"3\" "
                    "SizeC=\"2\" SizeT=\"1\" PhysicalSizeX=\"0.2\" PhysicalSizeY=\"0.2\" PhysicalSizeZ=\"1.5\"></Pixels></Image></OME>";
  writePages(t.file("two.ome.tif"), 0, 6, ome);
  expectSays("two.ome.tif", "two.ome.tif: an OME-TIFF of 2 channels and 1 time points");
  ome.description = std::regex_replace(ome.description, std::regex("SizeC=\"2\""), "SizeC=\"1\"");
  ome.description = std::regex_replace(ome.description, std::regex("SizeZ=\"3\""), "SizeZ=\"7\"");
  writePages(t.file("one.ome.tif"), 0, kNz, ome);
  EXPECT_EQ(loadVolume(parseScene("volume: {file: one.ome.tif}\n", t.path.string(), "s.yaml")).spacing,
            (std::array<double, 3>{0.2, 0.2, 1.5}));
  PageOptions frames;
  frames.description = "ImageJ=1.54f\nimages=6\nslices=3\nframes=2\nhyperstack=true\n";
  writePages(t.file("time.tif"), 0, 6, frames);
  expectSays("time.tif", "time.tif: an ImageJ hyperstack of 2 time points");
}

// Found by review as untested: a thumbnail page between the full-size ones (NewSubfileType
// "reduced") is skipped; a page of another size in one file is refused; .TIF in capitals.
TEST(TiffStack, ThumbnailsAreSkippedAndAPageOfAnotherSizeIsRefused) {
  TempDir t("tiff-pages-mixed");
  const auto v = samples();
  // One page of w x h: the volume's slice z where it has one, else a constant.
  auto page = [&](TIFF* f, int w, int h, int z, bool thumbnail) {
    TIFFSetField(f, TIFFTAG_IMAGEWIDTH, (uint32_t)w);
    TIFFSetField(f, TIFFTAG_IMAGELENGTH, (uint32_t)h);
    TIFFSetField(f, TIFFTAG_BITSPERSAMPLE, (uint16_t)16);
    TIFFSetField(f, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
    TIFFSetField(f, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    if (thumbnail) TIFFSetField(f, TIFFTAG_SUBFILETYPE, (uint32_t)FILETYPE_REDUCEDIMAGE);
    std::vector<uint16_t> row(w, 7);
    for (int y = 0; y < h; ++y) {
      if (w == kNx && h == kNy)
        for (int x = 0; x < w; ++x) row[x] = v[x + kNx * (y + kNy * z)];
      ASSERT_EQ(TIFFWriteScanline(f, row.data(), (uint32_t)y, 0), 1);
    }
    ASSERT_EQ(TIFFWriteDirectory(f), 1);
  };
  TIFF* f = TIFFOpen(t.file("thumbs.TIF").c_str(), "w");
  ASSERT_NE(f, nullptr);
  page(f, 4, 3, 0, true);  // a preview before the stack, as scanners write one
  for (int z = 0; z < kNz; ++z) {
    page(f, kNx, kNy, z, false);
    if (z == 2) page(f, 5, 5, 0, true);
  }
  TIFFClose(f);
  EXPECT_EQ(volumeFormatOf(t.file("thumbs.TIF")), VolumeFormat::Tiff);
  EXPECT_EQ(loadVolume(parseScene("volume: {file: thumbs.TIF}\n", t.path.string(), "s.yaml")).values, reference(t).values);

  f = TIFFOpen(t.file("sizes.tif").c_str(), "w");
  ASSERT_NE(f, nullptr);
  page(f, kNx, kNy, 0, false);
  page(f, kNx - 1, kNy, 1, false);
  TIFFClose(f);
  const std::string e = loadError("volume: {file: sizes.tif}\n", t.path.string());
  EXPECT_NE(e.find("sizes.tif: page 2 is 12 x 11 uint16, the first 13 x 11 uint16: a stack's pages are one size and type"),
            std::string::npos) << e;
}

}  // namespace tiff_test
}  // namespace
}  // namespace tessera
