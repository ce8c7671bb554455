// NIfTI and NRRD volumes, written here by the formats' own libraries (nifticlib, teem),
// load to exactly the volume of the same samples given as a raw file: values, spacing and
// axis order; windows read only their box; bad headers are refused by file and field.
#include <gtest/gtest.h>
#include <nifti2_io.h>
#include <teem/nrrd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <tuple>
#include <vector>

#include "common/io/volume_files.h"
#include "common/scene.h"
#include "common/scene_warnings.h"
#include "tests/common/load_error.h"
#include "tests/common/raw_spec.h"
#include "tests/common/temp_dir.h"
#include "tests/common/volume_files_util.h"

namespace tessera {
namespace {

using test::TempDir;
using namespace test::files;


TEST(VolumeFiles, NiftiPlainAndGzippedLoadAsTheRawFileOfTheSameSamples) {
  TempDir t("nifti");
  const Volume ref = rawReference(t);
  for (const char* name : {"head.nii", "head.nii.gz"}) {
    writeNifti(t.file(name));
    const Volume v = fromScene(std::string("volume: {file: ") + name + "}\n", t.path.string());
    expectSameVolume(v, ref);
    EXPECT_EQ(v.data_range[0], -900 - 400) << "signed values kept";
    // A window is the same part of the same volume.
    const VoxelBox box{{2, 3, 1}, {9, 11, 6}};
    const Volume w = fromScene(std::string("volume: {file: ") + name + "}\n", t.path.string(), &box);
    for (int z = 0; z < w.dims[2]; ++z)
      for (int y = 0; y < w.dims[1]; ++y)
        for (int x = 0; x < w.dims[0]; ++x) ASSERT_EQ(w.at(x, y, z), ref.at(x + 2, y + 3, z + 1)) << name;
  }
}

// One open file for many windows (the master's summary, isosurfaces and tessera-info read
// slabs front to back, so a gzip stream is decoded once): every window, in order or not,
// with or without a declared range, is loadVolume's window exactly.
TEST(VolumeFiles, AReaderServesEveryWindowAsLoadVolumeDoes) {
  TempDir t("reader");
  writeNifti(t.file("r.nii.gz"));
  for (const char* range : {"", ", range: [-1000, 2000]"}) {
    const Scene s = parseScene(std::string("volume: {file: r.nii.gz") + range + "}\n", t.path.string(), "s.yaml");
    VolumeReader reader(s);
    // Slabs front to back, then a slab before the last and a part-plane window.
    const std::vector<VoxelBox> boxes{{{0, 0, 0}, {kNx, kNy, 2}}, {{0, 0, 2}, {kNx, kNy, 5}}, {{0, 0, 5}, {kNx, kNy, kNz}},
                                      {{0, 0, 1}, {kNx, kNy, 3}}, {{2, 3, 4}, {9, 11, 7}}};
    for (const VoxelBox& box : boxes) {
      const Volume a = reader.read(box), b = loadVolume(s, box);
      EXPECT_EQ(a.dims, b.dims);
      EXPECT_EQ(a.origin, b.origin);
      EXPECT_EQ(a.data_range, b.data_range) << range;
      EXPECT_EQ(a.mapped_range, b.mapped_range) << range;
      EXPECT_EQ(a.values, b.values) << range << " z " << box.lo[2];
    }
  }
  // The whole volume through a reader that has read windows (and scanned the file): the
  // samples of the same volume as a raw file, normalised over their own range.
  const Scene whole = parseScene("volume: {file: r.nii.gz}\n", t.path.string(), "s.yaml");
  VolumeReader reader(whole);
  reader.read(VoxelBox{{0, 0, 3}, {kNx, kNy, 5}});
  expectSameVolume(reader.read(VoxelBox{{0, 0, 0}, {kNx, kNy, kNz}}), rawReference(t));
}

TEST(VolumeFiles, NiftiScalingIsApplied) {
  TempDir t("nifti-scaled");
  writeNifti(t.file("s.nii"), 2.0, -5.0);
  const RawVolumeSpec s = readVolumeHeader(t.file("s.nii"));
  EXPECT_EQ(s.slope, 2.0);
  EXPECT_EQ(s.inter, -5.0);
  const Volume v = fromScene("volume: {file: s.nii}\n", t.path.string());
  EXPECT_EQ(v.data_range[0], 2.0 * (-1300) - 5) << "the data's own range is of the scaled values";
  // tessera-info's effective scene names the file only: parsed again, the header decides.
  const Scene scene = parseScene("volume: {file: s.nii}\n", t.path.string(), "s.yaml");
  const std::string yaml = sceneYaml(scene);
  EXPECT_EQ(yaml.find("dims:"), std::string::npos) << yaml;
  EXPECT_EQ(std::get<RawVolumeSpec>(parseScene(yaml, t.path.string(), "again.yaml").volume).dims,
            (std::array<int, 3>{kNx, kNy, kNz}));
  // Read through a relative folder (tessera-info data/head.yaml), the file is printed with its
  // absolute path, so the printed scene saved anywhere names the same file.
  const std::string rel = std::filesystem::relative(t.path).string();
  const std::string printed = sceneYaml(parseScene("volume: {file: s.nii}\n", rel, "r.yaml"));
  std::filesystem::create_directories(t.path / "elsewhere");
  EXPECT_EQ(std::get<RawVolumeSpec>(parseScene(printed, (t.path / "elsewhere").string(), "e.yaml").volume).dims,
            (std::array<int, 3>{kNx, kNy, kNz}))
      << printed;
}

void writeNrrd(const std::string& path, bool gzip, bool detached) {
  auto v = samples();
  Nrrd* n = nrrdNew();
  ASSERT_EQ(nrrdWrap_va(n, v.data(), nrrdTypeShort, 3, (size_t)kNx, (size_t)kNy, (size_t)kNz), 0);
  nrrdAxisInfoSet_va(n, nrrdAxisInfoSpacing, kSpacing[0], kSpacing[1], kSpacing[2]);
  NrrdIoState* io = nrrdIoStateNew();
  nrrdIoStateEncodingSet(io, gzip ? nrrdEncodingGzip : nrrdEncodingRaw);
  nrrdIoStateSet(io, nrrdIoStateDetachedHeader, detached);
  ASSERT_EQ(nrrdSave(path.c_str(), n, io), 0) << path;
  nrrdIoStateNix(io);
  nrrdNix(n);  // the data is ours
}

TEST(VolumeFiles, NrrdAttachedDetachedRawAndGzipLoadAsTheRawFile) {
  TempDir t("nrrd");
  const Volume ref = rawReference(t);
  struct Case {
    const char* name;
    bool gzip, detached;
  };
  for (const Case c : {Case{"a.nrrd", false, false}, Case{"b.nrrd", true, false}, Case{"c.nhdr", false, true},
                       Case{"d.nhdr", true, true}}) {
    writeNrrd(t.file(c.name), c.gzip, c.detached);
    const RawVolumeSpec s = readVolumeHeader(t.file(c.name));
    EXPECT_EQ(s.gzip, c.gzip) << c.name;
    EXPECT_EQ(!s.data_file.empty(), c.detached) << c.name;
    expectSameVolume(fromScene(std::string("volume: {file: ") + c.name + "}\n", t.path.string()), ref);
  }
}

TEST(VolumeFiles, ABigEndianNrrdIsSwapped) {
  TempDir t("nrrd-big");
  const Volume ref = rawReference(t);
  auto v = samples();
  for (auto& x : v) x = (int16_t)(((uint16_t)x >> 8) | ((uint16_t)x << 8));
  t.write("big.raw", v.data(), v.size() * 2);
  std::ofstream(t.file("big.nhdr")) << "NRRD0004\ntype: short\ndimension: 3\nsizes: 13 11 7\n"
                                       "spacings: 0.75 1.25 2.5\nencoding: raw\nendian: big\ndata file: big.raw\n";
  expectSameVolume(fromScene("volume: {file: big.nhdr}\n", t.path.string()), ref);
}

using test::loadError;

TEST(VolumeFiles, BadHeadersAreNamedByFileAndField) {
  TempDir t("bad-headers");
  // dim[4] is time (a series: time_series_test.cpp); dim[5] (vector components) is not rendered.
  const int64_t dims[8] = {5, 4, 4, 4, 3, 2, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_UINT8, 1);
  nifti_set_filenames(nim, t.file("t.nii").c_str(), 0, 1);
  nifti_image_write(nim);
  nifti_image_free(nim);
  EXPECT_NE(loadError("volume: {file: t.nii}\n", t.path.string())
                .find("t.nii: holds 2 volumes (dim[4..7] = 3, 2, 1, 1); Tessera renders one 3-D volume per time step (dim[4])"),
            std::string::npos)
      << loadError("volume: {file: t.nii}\n", t.path.string());
  writeNifti(t.file("h.nii"));
  EXPECT_NE(loadError("volume: {file: h.nii, dims: [13, 11, 7]}\n", t.path.string())
                .find("volume.dims: comes from the header of"),
            std::string::npos);
  std::ofstream(t.file("junk.nii")) << "not a nifti file at all";
  EXPECT_NE(loadError("volume: {file: junk.nii}\n", t.path.string()).find("junk.nii: not a readable NIfTI"),
            std::string::npos);
  std::ofstream(t.file("flat.nrrd")) << "NRRD0004\ntype: float\ndimension: 2\nsizes: 4 4\nencoding: raw\n\n";
  EXPECT_NE(loadError("volume: {file: flat.nrrd}\n", t.path.string()).find("flat.nrrd: dimension 2"), std::string::npos);
  std::ofstream(t.file("hex.nhdr")) << "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: hex\n";
  EXPECT_NE(loadError("volume: {file: hex.nhdr}\n", t.path.string()).find("encoding 'hex'"), std::string::npos);
  // A gzip stream cut short: said when the samples are read.
  writeNifti(t.file("cut.nii.gz"));
  const auto full = std::filesystem::file_size(t.file("cut.nii.gz"));
  std::filesystem::resize_file(t.file("cut.nii.gz"), full / 2);
  const std::string cut = loadError("volume: {file: cut.nii.gz}\n", t.path.string());
  EXPECT_NE(cut.find("cut.nii.gz"), std::string::npos) << cut;
  EXPECT_TRUE(cut.find("compressed data") != std::string::npos || cut.find("not a readable NIfTI") != std::string::npos)
      << cut;
}

// Found by review: a header ending the file (no blank line, no data file) read from offset
// 2^64 - 1; "byte skip: abc" said only "stoll"; an RGB axis was drawn as 3 voxels of space.
TEST(VolumeFiles, NrrdHeadersWithoutDataOrWithBadFieldsAreNamed) {
  TempDir t("bad-nrrd");
  const std::string head = "NRRD0004\ntype: uchar\ndimension: 3\nencoding: raw\n";
  std::ofstream(t.file("nodata.nrrd")) << head << "sizes: 2 2 2";
  const std::string nodata = loadError("volume: {file: nodata.nrrd}\n", t.path.string());
  EXPECT_NE(nodata.find("nodata.nrrd: the header has no 'data file' field and no blank line"), std::string::npos)
      << nodata;
  const char bytes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  t.write("d.raw", bytes, sizeof bytes);
  for (const char* skip : {"abc", "12abc", "99999999999999999999"}) {
    std::ofstream(t.file("skip.nhdr")) << head << "sizes: 2 2 2\ndata file: d.raw\nbyte skip: " << skip << "\n";
    const std::string e = loadError("volume: {file: skip.nhdr}\n", t.path.string());
    EXPECT_NE(e.find(std::string("skip.nhdr: byte skip '") + skip + "' is not an integer"), std::string::npos) << e;
  }
  std::ofstream(t.file("rgb.nhdr")) << head << "sizes: 2 2 2\nkinds: RGB-color domain domain\ndata file: d.raw\n";
  const std::string rgb = loadError("volume: {file: rgb.nhdr}\n", t.path.string());
  EXPECT_NE(rgb.find("axis 0 is 'RGB-color'"), std::string::npos) << rgb;
  std::ofstream(t.file("ok.nhdr")) << head << "sizes: 2 2 2\nkinds: domain space ???\ndata file: d.raw\n";
  EXPECT_EQ(loadError("volume: {file: ok.nhdr}\n", t.path.string()), "<no error>");
  // Byte skip -1 (the data ends the file): a missing or short data file is named, with its size.
  for (const auto& [file, says] : {std::pair<std::string, std::string>{"gone.raw", "cannot read the size of the data file"},
                                   {"d.raw", "d.raw has 8 bytes, fewer than the 27 of its samples"}}) {
    std::ofstream(t.file("end.nhdr")) << head << "sizes: 3 3 3\ndata file: " << file << "\nbyte skip: -1\n";
    const std::string e = loadError("volume: {file: end.nhdr}\n", t.path.string());
    EXPECT_NE(e.find("end.nhdr: byte skip -1"), std::string::npos) << e;
    EXPECT_NE(e.find(says), std::string::npos) << e;
  }
}

// The scene's volume.spacing replaces a header's spacing, also one the header gets wrong; a
// 4-D file shorter than its steps is said at load, not at the step that runs out.
TEST(VolumeFiles, TheSceneReplacesABadHeaderSpacingAndShortFourDFilesAreSaidAtOnce) {
  TempDir t("spacing");
  const int64_t dims[8] = {3, 2, 2, 2, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_UINT8, 1);
  nim->dx = nim->pixdim[1] = 1;
  nim->dy = nim->pixdim[2] = 1;
  nim->dz = nim->pixdim[3] = 1e-9;
  nifti_set_filenames(nim, t.file("thin.nii").c_str(), 0, 1);
  nifti_image_write(nim);
  nifti_image_free(nim);
  const std::string bad = loadError("volume: {file: thin.nii}\n", t.path.string());
  EXPECT_NE(bad.find("thin.nii: the header's spacing [1, 1, 1e-09]: spacing ratio"), std::string::npos) << bad;
  EXPECT_NE(bad.find("give volume.spacing: [x, y, z] to replace it"), std::string::npos) << bad;
  EXPECT_EQ(fromScene("volume: {file: thin.nii, spacing: [1, 1, 2]}\n", t.path.string()).spacing,
            (std::array<double, 3>{1, 1, 2}));
  const char bytes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  t.write("d4.raw", bytes, sizeof bytes);
  std::ofstream(t.file("short.nhdr")) << "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 2 2 2 1000\nencoding: raw\n"
                                         "data file: d4.raw\n";
  const std::string e = loadError("volume: {file: short.nhdr}\n", t.path.string());
  EXPECT_NE(e.find("d4.raw has 8 bytes but 1000 time steps of 8 bytes need 8000"), std::string::npos) << e;
}

// A spacing the header leaves unknown (NIfTI's pixdim 0 or NaN; NRRD's nan, 0, "none" or no
// spacing field) is 1, and the warning names the axes, as for a TIFF; the scene's spacing
// silences it. It used to become 1 silently.
bool warnsNoSpacing(const TempDir& t, const std::string& volume, const std::string& axes) {
  const Scene s = parseScene("volume: " + volume + "\n", t.path.string(), "s.yaml");
  const std::vector<std::string> w = volumeWarnings(s, loadVolume(s));
  const std::string what = axes.empty() ? "gives no voxel spacing" : "gives no voxel spacing along " + axes + ": 1 assumed";
  return std::any_of(w.begin(), w.end(), [&](const std::string& x) { return x.find(what) != std::string::npos; });
}

TEST(VolumeFiles, ASpacingTheHeaderLeavesUnknownIsOneAndSaid) {
  TempDir t("unknown-spacing");
  const int64_t dims[8] = {3, 2, 2, 2, 1, 1, 1, 1};
  for (const auto& [name, dx, dz] : {std::tuple{"z0.nii", 2.0, 0.0}, std::tuple{"xnan.nii", std::nan(""), 3.0}}) {
    nifti_image* nim = nifti_make_new_nim(dims, DT_UINT8, 1);
    nim->dx = nim->pixdim[1] = dx;
    nim->dy = nim->pixdim[2] = 1;
    nim->dz = nim->pixdim[3] = dz;
    nifti_set_filenames(nim, t.file(name).c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
  }
  EXPECT_EQ(fromScene("volume: {file: z0.nii}\n", t.path.string()).spacing, (std::array<double, 3>{2, 1, 1}));
  EXPECT_TRUE(warnsNoSpacing(t, "{file: z0.nii}", "z"));
  EXPECT_EQ(fromScene("volume: {file: xnan.nii}\n", t.path.string()).spacing, (std::array<double, 3>{1, 1, 3}));
  EXPECT_TRUE(warnsNoSpacing(t, "{file: xnan.nii}", "x"));
  const char bytes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  t.write("v.raw", bytes, sizeof bytes);
  const std::string head = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: v.raw\n";
  std::ofstream(t.file("nan.nhdr")) << head << "spacings: 0.5 nan 2\n";
  std::ofstream(t.file("none.nhdr")) << head;
  std::ofstream(t.file("dirs.nhdr")) << head << "space dimension: 3\nspace directions: (0,0,3) none (0,0.5,0)\n";
  EXPECT_EQ(fromScene("volume: {file: nan.nhdr}\n", t.path.string()).spacing, (std::array<double, 3>{0.5, 1, 2}));
  EXPECT_TRUE(warnsNoSpacing(t, "{file: nan.nhdr}", "y"));
  EXPECT_TRUE(warnsNoSpacing(t, "{file: none.nhdr}", "x, y, z"));
  EXPECT_EQ(fromScene("volume: {file: dirs.nhdr}\n", t.path.string()).spacing, (std::array<double, 3>{3, 1, 0.5}));
  EXPECT_TRUE(warnsNoSpacing(t, "{file: dirs.nhdr}", "y"));
  writeNifti(t.file("known.nii"));  // every spacing given: no warning
  EXPECT_FALSE(warnsNoSpacing(t, "{file: known.nii}", ""));
  EXPECT_FALSE(warnsNoSpacing(t, "{file: none.nhdr, spacing: [1, 1, 1]}", ""));
}

// Found by a review against nifticlib's and teem's sources: files other tools write, which
// were refused or misread. Each handmade NRRD is also read by teem itself, so the test holds
// the reader to teem's reading, not to ours.
std::vector<int16_t> teemSamples(const std::string& path) {
  Nrrd* n = nrrdNew();
  std::vector<int16_t> v;
  if (nrrdLoad(n, path.c_str(), nullptr) == 0 && n->type == nrrdTypeShort)
    v.assign(static_cast<int16_t*>(n->data), static_cast<int16_t*>(n->data) + nrrdElementNumber(n));
  nrrdNuke(n);
  return v;
}

void gzipFile(const std::string& from, const std::string& to, const std::string& prefix = "") {
  std::ifstream in(from, std::ios::binary);
  const std::string bytes = prefix + std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  gzFile z = gzopen(to.c_str(), "wb");
  ASSERT_NE(z, nullptr);
  ASSERT_EQ(gzwrite(z, bytes.data(), (unsigned)bytes.size()), (int)bytes.size());
  gzclose(z);
}

TEST(VolumeFiles, FilesOtherToolsWriteLoadAsTheRawFile) {
  TempDir t("other-tools");
  const Volume ref = rawReference(t);
  // NIfTI: a .hdr whose .img was gzipped afterwards; a gzipped .nii named .nii.
  writeNifti(t.file("p.hdr"));
  gzipFile(t.file("p.img"), t.file("p.img.gz"));
  std::filesystem::remove(t.file("p.img"));
  expectSameVolume(fromScene("volume: {file: p.hdr}\n", t.path.string()), ref);
  // nifticlib decompresses by the name, so a gzipped file named .nii is refused; said so.
  writeNifti(t.file("g.nii.gz"));
  std::filesystem::rename(t.file("g.nii.gz"), t.file("g.nii"));
  const std::string gz = loadError("volume: {file: g.nii}\n", t.path.string());
  EXPECT_NE(gz.find("g.nii: gzip-compressed, but its name does not end in .gz"), std::string::npos) << gz;

  // NRRD: teem's other spellings of field names, upper-case values, spaces inside a vector
  // and in a file name, a byte skip, vectors of a 4-D space, unknown spacings.
  const auto v = samples();
  const std::string junk = "12345";
  t.write("my scan.raw", (junk + std::string(reinterpret_cast<const char*>(v.data()), v.size() * 2)).data(),
          junk.size() + v.size() * 2);
  std::ofstream(t.file("spell.nhdr")) << "NRRD0004\ntype: SHORT\ndimension: 3\nsizes: 13 11 7\nspace: 3D-right-handed\n"
                                         "spacedirections: (0.75,0,0) (0, 1.25, 0) (0,0,2.5)\nencoding: RAW\n"
                                         "endian: LITTLE\nbyteskip: 5\ndatafile: my scan.raw\n";
  std::ofstream(t.file("space4.nhdr")) << "NRRD0005\ntype: short\ndimension: 3\nsizes: 13 11 7\nspace dimension: 4\n"
                                          "space directions: (0.75,0,0,0) (0,1.25,0,0) (0,0,2.5,0)\nencoding: raw\n"
                                          "endian: little\nbyte skip: 5\ndata file: my scan.raw\n";
  gzipFile(t.file("ref.raw"), t.file("skip.raw.gz"), junk);
  std::ofstream(t.file("gzskip.nhdr")) << "NRRD0004\ntype: short\ndimension: 3\nsizes: 13 11 7\n"
                                          "spacings: 0.75 1.25 2.5\nencoding: gzip\nendian: little\nbyte skip: 5\n"
                                          "data file: skip.raw.gz\n";
  for (const char* name : {"spell.nhdr", "space4.nhdr", "gzskip.nhdr"}) {
    EXPECT_EQ(teemSamples(t.file(name)), v) << name << ": teem reads it otherwise";
    expectSameVolume(fromScene(std::string("volume: {file: '") + name + "'}\n", t.path.string()), ref);
  }
  std::ofstream(t.file("nan.nhdr")) << "NRRD0004\ntype: short\ndimension: 3\nsizes: 13 11 7\nspacings: 0.75 1.25 nan\n"
                                       "encoding: raw\nendian: little\ndata file: ref.raw\n";
  EXPECT_EQ(readVolumeHeader(t.file("nan.nhdr")).spacing, (std::array<double, 3>{0.75, 1.25, 1}));
  expectSameVolume(fromScene("volume: {file: nan.nhdr, spacing: [0.75, 1.25, 2.5]}\n", t.path.string()), ref);
}

TEST(VolumeFiles, TwoDimensionalNiftiIsOneSliceThick) {
  // dim[0] = 2 with dim[3] = 0, as some writers leave the axes beyond dim[0].
  TempDir t("nifti-2d");
  nifti_1_header h{};
  h.sizeof_hdr = 348;
  h.dim[0] = 2, h.dim[1] = 5, h.dim[2] = 4;
  h.datatype = DT_UINT8, h.bitpix = 8;
  h.pixdim[1] = 0.5f, h.pixdim[2] = 0.25f;
  h.vox_offset = 352;
  std::memcpy(h.magic, "n+1\0", 4);
  std::string bytes(reinterpret_cast<const char*>(&h), sizeof h);
  bytes += std::string(4, '\0');
  for (int i = 0; i < 20; ++i) bytes += (char)(i * 10);
  t.write("flat.nii", bytes.data(), bytes.size());
  const RawVolumeSpec s = readVolumeHeader(t.file("flat.nii"));
  EXPECT_EQ(s.dims, (std::array<int, 3>{5, 4, 1}));
  EXPECT_EQ(s.spacing, (std::array<double, 3>{0.5, 0.25, 1}));
  const Volume vol = fromScene("volume: {file: flat.nii}\n", t.path.string());
  EXPECT_EQ(vol.dims, (std::array<int, 3>{5, 4, 1}));
  EXPECT_FLOAT_EQ(vol.values[19], 1.0f);
}

TEST(VolumeFiles, InconsistentNrrdHeadersAreNamed) {
  TempDir t("nrrd-inconsistent");
  const std::string head = "NRRD0004\ntype: uchar\nencoding: raw\ndata file: d.raw\n";
  const char bytes[24] = {};
  t.write("d.raw", bytes, sizeof bytes);
  auto error = [&](const std::string& name, const std::string& fields, bool series = false) {
    std::ofstream(t.file(name)) << head << fields;
    try {
      int steps = 0;
      readVolumeHeader(t.file(name), series ? &steps : nullptr);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  EXPECT_NE(error("extra.nhdr", "dimension: 3\nsizes: 2 2 2 3\n").find("extra.nhdr: sizes '2 2 2 3': expected 3 sizes"),
            std::string::npos);
  EXPECT_NE(error("twice.nhdr", "dimension: 3\nsizes: 2 2 2\nType: short\n").find("twice.nhdr: field 'Type' appears twice"),
            std::string::npos);
  const std::string vec = error("vec.nhdr", "dimension: 4\nsizes: 2 2 2 3\nkinds: space space space vector\n", true);
  EXPECT_NE(vec.find("vec.nhdr: kinds 'space space space vector': axis 3 is 'vector'"), std::string::npos) << vec;
  EXPECT_EQ(error("time.nhdr", "dimension: 4\nsizes: 2 2 2 3\nkinds: space space space time\n", true), "<no error>");
  std::ofstream(t.file("many.nhdr")) << "NRRD0004\ntype: uchar\nencoding: raw\ndimension: 3\nsizes: 2 2 2\n"
                                        "data file: d%03d.raw 1 3 1\n";
  try {
    readVolumeHeader(t.file("many.nhdr"));
    ADD_FAILURE() << "a data file pattern was taken for one file";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("data file 'd%03d.raw 1 3 1': one file expected"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera
