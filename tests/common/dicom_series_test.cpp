// DICOM series written by GDCM itself (no downloaded data): slices in any file order,
// uncompressed (explicit and implicit VR) and compressed, scaled, read whole and as windows;
// folders of two series, a missing slice and a multi-frame file refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <fstream>
#include <string>
#include <vector>

#include "common/io/volume_files.h"
#include "common/scene_warnings.h"
#include "common/value_histogram.h"
#include "common/scene.h"
#include "tests/common/dicom_writer.h"
#include "tests/common/temp_dir.h"

namespace tessera {
namespace {

namespace fs = std::filesystem;

constexpr int kCols = 6, kRows = 5;

// A file name such as "IM1000". Appended, not "IM" + std::to_string(k): GCC 12 at -O3 warns
// of an overlapping copy in that operator+ once inlined (-Wrestrict, GCC bug 105329).
std::string numbered(const char* prefix, int k) {
  std::string name = prefix;
  name += std::to_string(k);
  return name;
}

// Stored value of voxel (x, y) of slice k: distinct everywhere, some negative.
int16_t stored(int x, int y, int k) { return (int16_t)(x + 10 * y + 100 * k - 250); }

struct SliceFile {
  int k = 0;  // position: z = 10 + 2.5 k (mm)
  std::string series = "1.2.826.0.1.3680043.2.1125.1";
  std::string description = "axial";
  gdcm::TransferSyntax::TSType syntax = gdcm::TransferSyntax::ExplicitVRLittleEndian;
  double slope = 2, inter = -1024;
};

void writeSlice(const fs::path& file, const SliceFile& s) {
  test::DicomSlice d;
  d.cols = kCols, d.rows = kRows;
  for (int y = 0; y < kRows; ++y)
    for (int x = 0; x < kCols; ++x) d.values.push_back(stored(x, y, s.k));
  d.z = 10 + 2.5 * s.k;
  d.series = s.series, d.description = s.description, d.syntax = s.syntax, d.slope = s.slope, d.inter = s.inter;
  test::writeDicomSlice(file, d);
}

// Slices 0..n-1 written in a shuffled order under names that do not sort by position.
fs::path writeSeries(const test::TempDir& t, const std::string& folder, int n, SliceFile s = {}) {
  const fs::path dir = t.path / folder;
  fs::create_directories(dir);
  for (int i = 0; i < n; ++i) {
    s.k = (i * 3 + 1) % n;  // n not divisible by 3: every k once
    writeSlice(dir / numbered("IM", 1000 - i), s);
  }
  return dir;
}

Scene sceneOf(const fs::path& file) {
  return parseScene("volume: {file: " + file.string() + "}\n", ".", "dicom.yaml");
}

void expectValues(const Volume& v, const VoxelBox& box, double slope, double inter) {
  for (int z = box.lo[2]; z < box.hi[2]; ++z)
    for (int y = box.lo[1]; y < box.hi[1]; ++y)
      for (int x = box.lo[0]; x < box.hi[0]; ++x)
        ASSERT_EQ(v.at(x - box.lo[0], y - box.lo[1], z - box.lo[2]) + v.value_offset, slope * stored(x, y, z) + inter)
            << x << "," << y << "," << z;
}

TEST(DicomSeries, AFolderIsAVolumeOfItsSlicesInOrderScaled) {
  test::TempDir t("dicom");
  for (auto syntax : {gdcm::TransferSyntax::ExplicitVRLittleEndian, gdcm::TransferSyntax::ImplicitVRLittleEndian,
                      gdcm::TransferSyntax::RLELossless, gdcm::TransferSyntax::JPEGLosslessProcess14_1}) {
    SCOPED_TRACE(gdcm::TransferSyntax::GetTSString(syntax));
    SliceFile s;
    s.syntax = syntax;
    const fs::path dir = writeSeries(t, numbered("ct", (int)syntax), 7, s);
    const Scene scene = sceneOf(dir);
    const auto& spec = std::get<RawVolumeSpec>(scene.volume);
    EXPECT_EQ(spec.format, VolumeFormat::Dicom);
    EXPECT_EQ(spec.dims, (std::array<int, 3>{kCols, kRows, 7}));
    EXPECT_EQ(spec.type, VoxelType::Int16);
    EXPECT_NEAR(spec.spacing[0], 0.5, 1e-9);
    EXPECT_NEAR(spec.spacing[1], 0.7, 1e-9);
    EXPECT_NEAR(spec.spacing[2], 2.5, 1e-9);
    const bool compressed = syntax != gdcm::TransferSyntax::ExplicitVRLittleEndian &&
                            syntax != gdcm::TransferSyntax::ImplicitVRLittleEndian;
    EXPECT_EQ(spec.slices[0].encoded, compressed);
    // Seen as a 3D viewer first shows a patient: from the front (anterior: -y, up the rows of
    // an axial slice) and a little above, head (+z, along the normal) up; a folder given
    // alone turns about that axis.
    EXPECT_EQ(scene.camera.up, (Vec3{0, 0, 1}));
    EXPECT_LT(scene.camera.eye.y, 0);
    EXPECT_GT(std::abs(scene.camera.eye.y), 3 * std::abs(scene.camera.eye.x));
    EXPECT_EQ(loadScene(dir.string()).orbit.axis, (Vec3{0, 0, 1}));
    RawVolumeReader reader(spec);
    const VoxelBox whole{{0, 0, 0}, spec.dims};
    expectValues(reader.readValues(whole), whole, 2, -1024);
    const VoxelBox window{{1, 2, 2}, {4, 5, 6}};  // what a renderer of one brick reads
    expectValues(reader.readValues(window), window, 2, -1024);
    // Normalised over the data's own range, as every format.
    const Volume v = loadVolume(scene);
    EXPECT_EQ(v.data_range[0], 2.0 * stored(0, 0, 0) - 1024);
    EXPECT_EQ(v.data_range[1], 2.0 * stored(kCols - 1, kRows - 1, 6) - 1024);
  }
}

TEST(DicomSeries, OneFileNamesItsSeriesAndAFolderOfTwoSeriesIsRefusedWithBoth) {
  test::TempDir t("dicom2");
  SliceFile a, b;
  b.series = "1.2.826.0.1.3680043.2.1125.2";
  b.description = "scout";
  b.inter = 0;
  const fs::path dir = writeSeries(t, "study", 4, a);
  for (int k = 0; k < 2; ++k) b.k = k, writeSlice(dir / (numbered("SC", k) + ".dcm"), b);
  try {
    sceneOf(dir);
    FAIL() << "two series in one folder were read as one";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("holds 2 series; name one file of the one to show"), std::string::npos) << m;
    EXPECT_NE(m.find("4 slices, 'axial'"), std::string::npos) << m;
    EXPECT_NE(m.find("2 slices, 'scout'"), std::string::npos) << m;
  }
  const RawVolumeSpec scout = std::get<RawVolumeSpec>(sceneOf(dir / "SC1.dcm").volume);
  EXPECT_EQ(scout.dims[2], 2);
  EXPECT_EQ(scout.slices[0].inter, 0);
  const RawVolumeSpec axial = std::get<RawVolumeSpec>(sceneOf(dir / "IM1000").volume);
  EXPECT_EQ(axial.dims[2], 4);
}

TEST(DicomSeries, AMissingSliceOrTwoAtOnePlaceIsSaid) {
  test::TempDir t("dicom3");
  const fs::path dir = writeSeries(t, "gap", 5);
  fs::remove(dir / "IM998");  // the slice at k = (2 * 3 + 1) % 5 = 2
  try {
    sceneOf(dir);
    FAIL() << "a series with a gap was read";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("slices are not evenly spaced"), std::string::npos) << e.what();
  }
  SliceFile twice;
  twice.k = 0;
  writeSlice(dir / "IM998", twice);  // a second slice where k = 0 is
  try {
    sceneOf(dir);
    FAIL() << "two slices at one position were read";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("two acquisitions in one series?"), std::string::npos) << e.what();
  }
}

TEST(DicomSeries, AFolderWithoutImagesAndKeysTheHeaderGivesAreRefused) {
  test::TempDir t("dicom4");
  fs::create_directories(t.path / "empty");
  std::ofstream(t.path / "empty" / "notes.txt") << "not DICOM";
  try {
    sceneOf(t.path / "empty");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("no DICOM image in it or its sub-folders (0 files with DICOM's marker"),
              std::string::npos)
        << e.what();
  }
  const fs::path dir = writeSeries(t, "ct", 2);
  try {
    parseScene("volume: {file: " + dir.string() + ", dims: [6, 5, 2]}\n", ".", "d.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory: read as a DICOM series or a TIFF stack, whose headers give dims and type"),
              std::string::npos)
        << e.what();
  }
  try {  // a file of it, with no extension: known by its "DICM"
    parseScene("volume: {file: " + (dir / "IM1000").string() + ", type: int16}\n", ".", "d.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("volume.type: comes from the header"), std::string::npos) << e.what();
  }
}

// Each slice's own rescaling (PET and MR scale slice by slice), and 12-bit signed samples
// whose upper bits hold something else: the value is the low 12 bits, sign-extended,
// whether GDCM decodes the slice or it is read in place.
TEST(DicomSeries, EachSliceKeepsItsScalingAndOnlyItsStoredBitsCount) {
  test::TempDir t("dicom5");
  for (auto syntax : {gdcm::TransferSyntax::ExplicitVRLittleEndian, gdcm::TransferSyntax::RLELossless}) {
    const fs::path dir = t.path / (syntax == gdcm::TransferSyntax::RLELossless ? "rle" : "plain");
    fs::create_directories(dir);
    for (int k = 0; k < 3; ++k) {
      test::DicomSlice d;
      d.cols = 4, d.rows = 2, d.z = 3.0 * k, d.syntax = syntax, d.slope = 0.5 * (k + 1), d.inter = 10.0 * k;
      d.bits_stored = 12;
      for (int i = 0; i < 8; ++i) {
        const int value = (i - 4) * 300 + k;             // -1200 .. 900: 12-bit signed
        d.values.push_back((int16_t)((value & 0x0fff) | 0x5000));  // not sign-extended, bits 12-15 junk
      }
      test::writeDicomSlice(dir / numbered("S", k), d);
    }
    const Scene scene = sceneOf(dir);
    RawVolumeReader reader(std::get<RawVolumeSpec>(scene.volume));
    const Volume v = reader.readValues(VoxelBox{{0, 0, 0}, {4, 2, 3}});
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 8; ++i)
        ASSERT_EQ(v.at(i % 4, i / 4, k) + v.value_offset, 0.5 * (k + 1) * ((i - 4) * 300 + k) + 10.0 * k)
            << gdcm::TransferSyntax::GetTSString(syntax) << " slice " << k << " voxel " << i;
    EXPECT_FALSE(storesIntegers(std::get<RawVolumeSpec>(scene.volume))) << "slopes of 0.5 make halves";
  }
}

// Slices that move down their plane as they go (a head CT's gantry tilt of 15 degrees) are
// stacked straight, and the warning says so with the angle.
TEST(DicomSeries, AGantryTiltIsNamedByItsAngle) {
  test::TempDir t("dicom7");
  fs::create_directories(t.path / "tilt");
  for (int k = 0; k < 4; ++k) {
    test::DicomSlice d;
    d.cols = 3, d.rows = 3, d.values.assign(9, (int16_t)(100 * k)), d.z = 2.0 * k;
    d.y = -30 + 2.0 * k * std::tan(15 * std::numbers::pi / 180);
    test::writeDicomSlice(t.path / "tilt" / numbered("S", k), d);
  }
  // A colour map given: a CT series alone would also get a note on its default (below).
  auto withColours = [](const fs::path& dir) {
    return parseScene("volume: {file: " + dir.string() + "}\ntransfer_function: grayscale\n", ".", "dicom.yaml");
  };
  Scene scene = withColours(t.path / "tilt");
  const auto& spec = std::get<RawVolumeSpec>(scene.volume);
  EXPECT_NEAR(spec.dicom_tilt_degrees, 15, 1e-3);
  EXPECT_NEAR(spec.spacing[2], 2.0, 1e-9) << "the distance along the normal";
  Volume shape;
  shape.dims = spec.dims, shape.spacing = spec.spacing, shape.data_range = shape.mapped_range = {0, 300};
  const auto w = volumeWarnings(scene, shape);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("dicom.yaml: volume: the DICOM slices shift in their own plane from one to the next (a gantry "
                      "tilt of 15 degrees)"),
            std::string::npos)
      << w[0];
  EXPECT_TRUE(volumeWarnings(withColours(writeSeries(t, "straight", 2)), shape).empty());
}

// A CT series given no colour map and no range is shown as 3D Slicer's CT-Bone shows it: the
// preset's points in Hounsfield units over its own range, and a note says so. A
// scene's own colour map or range is left alone; a CT preset with a range, or on a volume
// without Hounsfield units, is refused.
TEST(DicomSeries, ACtSeriesAloneIsShownWithTheBonePresetInHounsfieldUnits) {
  test::TempDir t("dicom-ct");
  const fs::path dir = writeSeries(t, "ct", 4);
  const Scene alone = sceneOf(dir);
  const auto& spec = std::get<RawVolumeSpec>(alone.volume);
  EXPECT_EQ(spec.modality, "CT");
  EXPECT_EQ(alone.tf, transferFunctionPreset("ct-bone"));
  EXPECT_TRUE(spec.has_range);
  EXPECT_EQ(spec.range, kCtRange);
  EXPECT_FALSE(alone.shading.on) << "shading is the scene's choice";
  ASSERT_EQ(spec.notes.size(), 1u);
  EXPECT_NE(spec.notes[0].find("a CT series with no transfer_function: shown with ct-bone"), std::string::npos);
  // 641 HU (the preset's opaque bone point) at its place in the range.
  EXPECT_NEAR(alone.tf.points()[2].s, (641.385 + 3024) / 6095, 1e-12);

  const auto scene = [&](const std::string& more) {
    return parseScene("volume: {file: " + dir.string() + more, ".", "dicom.yaml");
  };
  EXPECT_EQ(scene(", range: [-200, 1200]}\n").tf, transferFunctionPreset("cool-to-warm")) << "the scene's range keeps the default colour map";
  EXPECT_EQ(scene("}\ntransfer_function: viridis\n").tf, transferFunctionPreset("viridis"));
  const Scene soft = scene("}\ntransfer_function: ct-soft-tissue\nshading: true\n");
  EXPECT_EQ(soft.tf, transferFunctionPreset("ct-soft-tissue"));
  EXPECT_EQ(std::get<RawVolumeSpec>(soft.volume).range, kCtRange);
  EXPECT_TRUE(soft.shading.on);
  EXPECT_TRUE(std::get<RawVolumeSpec>(soft.volume).notes.empty());
  EXPECT_THROW(scene(", range: [0, 1000]}\ntransfer_function: ct-bone\n"), SceneError);
  EXPECT_THROW(parseScene("volume: {generator: {name: head, size: 16}}\ntransfer_function: ct-bone\n", ".", "g.yaml"),
               SceneError);
  // One slice (a localizer) is seen face on, as an image: not edge-on from the patient's front.
  const Scene one = sceneOf(writeSeries(t, "one", 1));
  EXPECT_EQ(one.camera.up, (Vec3{0, -1, 0}));
  EXPECT_LT(one.camera.eye.z, 0);
}

// A CD's export: DICOMDIR at the top, the images in sub-folders; a multi-frame file refused.
TEST(DicomSeries, AnExportsSubFoldersAreSearchedAndAMultiFrameFileIsRefused) {
  test::TempDir t("dicom6");
  writeSeries(t, "cd/DICOM/ST000001/SE000001", 4);
  std::ofstream(t.path / "cd" / "DICOMDIR") << "not an image";
  const RawVolumeSpec s = std::get<RawVolumeSpec>(sceneOf(t.path / "cd").volume);
  EXPECT_EQ(s.dims, (std::array<int, 3>{kCols, kRows, 4}));
  test::DicomSlice multi;
  multi.cols = 2, multi.rows = 2, multi.frames = 3, multi.values.assign(12, 7);
  fs::create_directories(t.path / "mf");
  test::writeDicomSlice(t.path / "mf" / "enhanced.dcm", multi);
  try {
    sceneOf(t.path / "mf");
    FAIL() << "a multi-frame file was read as a series";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("a multi-frame image (NumberOfFrames 3)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera
