// Time series: which step a frame shows (loop, once, swing, backwards), series in every form
// (pattern, list, ParaView .series, 4-D NIfTI written by nifticlib, 4-D NRRD written by teem,
// multi-page TIFFs written by libtiff)
// loading as the same steps given as raw files, and the bad inputs named by file and field.
#include <gtest/gtest.h>
#include <nifti2_io.h>
#include <teem/nrrd.h>
#include <tiffio.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "common/scene.h"
#include "tests/common/temp_dir.h"

namespace tessera {
namespace {

using test::TempDir;

constexpr int kSx = 9, kSy = 7, kSz = 5, kSteps = 4;

// A different value at every voxel of every step, so a step or axis mix-up shows.
std::vector<int16_t> stepSamples(int step) {
  std::vector<int16_t> v((size_t)kSx * kSy * kSz);
  for (int z = 0; z < kSz; ++z)
    for (int y = 0; y < kSy; ++y)
      for (int x = 0; x < kSx; ++x)
        v[x + kSx * (y + kSy * z)] = (int16_t)(x * 3 - y * 40 + z * 500 + step * 1000 - 900);
  return v;
}

std::vector<int16_t> allSteps() {
  std::vector<int16_t> all;
  for (int s = 0; s < kSteps; ++s) {
    auto v = stepSamples(s);
    all.insert(all.end(), v.begin(), v.end());
  }
  return all;
}

void writeRawSteps(const TempDir& t) {
  for (int s = 0; s < kSteps; ++s) {
    auto v = stepSamples(s);
    t.write(std::string("t") + std::to_string(s) + ".raw", v.data(), v.size() * 2);
  }
}

// Step `step` as a multi-page int16 TIFF (LZW, strips of 2 rows), as a light-sheet
// microscope's time-lapse saves one stack a time point.
void writeTiffStep(const std::string& path, int step) {
  TIFF* t = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(t, nullptr);
  const auto v = stepSamples(step);
  for (int z = 0; z < kSz; ++z) {
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)kSx);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)kSy);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)16);
    TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_INT);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_LZW);
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)2);
    for (int y = 0; y < kSy; ++y)
      ASSERT_EQ(TIFFWriteScanline(t, const_cast<int16_t*>(v.data() + kSx * (y + kSy * z)), (uint32_t)y, 0), 1);
    ASSERT_EQ(TIFFWriteDirectory(t), 1);
  }
  TIFFClose(t);
}

void writeNifti4d(const std::string& path) {
  const int64_t dims[8] = {4, kSx, kSy, kSz, kSteps, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
  ASSERT_NE(nim, nullptr);
  nim->dx = nim->pixdim[1] = 0.5;
  const auto v = allSteps();
  std::memcpy(nim->data, v.data(), v.size() * 2);
  ASSERT_EQ(nifti_set_filenames(nim, path.c_str(), 0, 1), 0);
  nifti_image_write(nim);
  nifti_image_free(nim);
}

void writeNifti3d(const std::string& path, int step, int nz = kSz, double dx = 0.5) {
  const int64_t dims[8] = {3, kSx, kSy, nz, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
  ASSERT_NE(nim, nullptr);
  nim->dx = nim->pixdim[1] = dx;
  const auto v = stepSamples(step);
  std::memcpy(nim->data, v.data(), (size_t)kSx * kSy * nz * 2);
  ASSERT_EQ(nifti_set_filenames(nim, path.c_str(), 0, 1), 0);
  nifti_image_write(nim);
  nifti_image_free(nim);
}

void writeNrrd4d(const std::string& path) {
  auto v = allSteps();
  Nrrd* n = nrrdNew();
  ASSERT_EQ(nrrdWrap_va(n, v.data(), nrrdTypeShort, 4, (size_t)kSx, (size_t)kSy, (size_t)kSz, (size_t)kSteps), 0);
  nrrdAxisInfoSet_va(n, nrrdAxisInfoSpacing, 0.5, 1.0, 1.0, AIR_NAN);
  ASSERT_EQ(nrrdSave(path.c_str(), n, nullptr), 0) << path;
  nrrdNix(n);  // the data is ours
}

const std::string kRaw = "  dims: [9, 7, 5]\n  type: int16\n  spacing: [0.5, 1, 1]\n";

Scene scene(const TempDir& t, const std::string& volume, const std::string& rest = "") {
  return parseScene("volume:\n" + volume + rest, t.path.string(), "s.yaml");
}

std::string errorOf(const TempDir& t, const std::string& volume, const std::string& rest = "") {
  try {
    scene(t, volume, rest);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(Playback, LoopOnceSwingAndBackwards) {
  Playback p;
  p.play = true;
  std::vector<int> got;
  for (int k = 0; k < 7; ++k) got.push_back(p.stepAt(k, 3));
  EXPECT_EQ(got, (std::vector<int>{0, 1, 2, 0, 1, 2, 0}));
  p.mode = Playback::Mode::Swing;
  got.clear();
  for (int k = 0; k < 9; ++k) got.push_back(p.stepAt(k, 4));
  EXPECT_EQ(got, (std::vector<int>{0, 1, 2, 3, 2, 1, 0, 1, 2}));
  EXPECT_EQ(p.onePass(4), 6);
  p.mode = Playback::Mode::Once;
  EXPECT_EQ(p.stepAt(10, 4), 3);
  p.mode = Playback::Mode::Loop;
  p.stride = -1;
  p.step = 1;
  got.clear();
  for (int k = 0; k < 5; ++k) got.push_back(p.stepAt(k, 4));
  EXPECT_EQ(got, (std::vector<int>{1, 0, 3, 2, 1}));
  p.stride = 3;
  EXPECT_EQ(p.onePass(10), 4);
  p.play = false;
  EXPECT_EQ(p.stepAt(5, 4), 1) << "paused: the first step";
}

TEST(TimeSeries, EveryFormLoadsTheSameStepsAsRawFiles) {
  TempDir t("series-forms");
  writeRawSteps(t);
  writeNifti4d(t.file("four.nii"));
  writeNifti4d(t.file("four.nii.gz"));
  writeNrrd4d(t.file("four.nrrd"));
  for (int s = 0; s < kSteps; ++s) writeNifti3d(t.file(std::string("n") + std::to_string(s) + ".nii"), s);
  for (int s = 0; s < kSteps; ++s) writeTiffStep(t.file(std::string("f") + std::to_string(s) + ".tif"), s);
  std::ofstream(t.file("run.series")) << R"({"file-series-version": "1.0", "files": [
    {"name": "t0.raw", "time": 0}, {"name": "t1.raw", "time": 0.25}, {"name": "t2.raw", "time": 0.5}, {"name": "t3.raw", "time": 1}]})";
  const Scene ref = scene(t, "  series: [t0.raw, t1.raw, t2.raw, t3.raw]\n" + kRaw);
  EXPECT_EQ(ref.series.steps, kSteps);
  const std::vector<std::string> forms = {
      "  series: {pattern: t%d.raw, first: 0, last: 3}\n" + kRaw, "  series: run.series\n" + kRaw,
      "  file: four.nii\n", "  file: four.nii.gz\n", "  file: four.nrrd\n",
      "  series: {pattern: n%d.nii, first: 0, last: 3}\n",
      "  series: {pattern: f%d.tif, first: 0, last: 3}\n  spacing: [0.5, 1, 1]\n"};
  const VoxelBox whole{{0, 0, 0}, {kSx, kSy, kSz}}, window{{2, 1, 1}, {7, 6, 4}};
  for (const auto& form : forms) {
    Scene s = scene(t, form);
    ASSERT_EQ(s.series.steps, kSteps) << form;
    for (int step = 0; step < kSteps; ++step)
      for (const VoxelBox& box : {whole, window}) {
        const Volume a = loadVolume(s, box, step), b = loadVolume(ref, box, step);
        EXPECT_EQ(a.values, b.values) << form << " step " << step;
        EXPECT_EQ(a.spacing, b.spacing) << form;
      }
    // One reader for every step (a renderer reads a gzip 4-D file's steps through one
    // stream): forwards, back and forwards again, each window as loadVolume reads it alone.
    VolumeReader reader(s);
    for (int step : {0, 1, 2, 3, 1, 0, 3})
      for (const VoxelBox& box : {window, whole}) {
        const Volume a = reader.read(box, step), b = loadVolume(s, box, step);
        EXPECT_EQ(a.values, b.values) << form << " step " << step;
        EXPECT_EQ(a.data_range, b.data_range) << form << " step " << step;
        EXPECT_EQ(a.mapped_range, b.mapped_range) << form << " step " << step;
      }
  }
  EXPECT_EQ(scene(t, "  series: run.series\n" + kRaw).series.times, (std::vector<double>{0, 0.25, 0.5, 1}));
}

// The pattern is formatted as written and then joined to the scene's folder: a '%' in a
// folder's name (a URL-encoded download, "run%20one") is no conversion of its.
TEST(TimeSeries, APercentInTheScenesFolderIsNotPartOfThePattern) {
  for (const char* folder : {"series-run%20one", "series-q%x", "series-%d"}) {
    TempDir t(folder);
    writeRawSteps(t);
    const Scene s = scene(t, "  series: {pattern: t%d.raw, first: 0, last: 3}\n" + kRaw);
    ASSERT_EQ(s.series.steps, kSteps) << folder;
    EXPECT_EQ(s.series.files.back(), t.file("t3.raw")) << folder;
    const Scene ref = scene(t, "  series: [t0.raw, t1.raw, t2.raw, t3.raw]\n" + kRaw);
    EXPECT_EQ(loadVolume(s, VoxelBox{{0, 0, 0}, {kSx, kSy, kSz}}, 2).values,
              loadVolume(ref, VoxelBox{{0, 0, 0}, {kSx, kSy, kSz}}, 2).values);
    // The effective scene says the pattern, not a line per step (tessera-info printed
    // 1,000,000 lines for a pattern of as many steps), and names the same files parsed again.
    const std::string yaml = sceneYaml(s);
    EXPECT_NE(yaml.find("series: {pattern: "), std::string::npos) << yaml;
    EXPECT_EQ(yaml.find("t1.raw"), std::string::npos) << yaml;
    const Scene again = parseScene(yaml, "/elsewhere", "again.yaml");
    EXPECT_EQ(again.series.files, s.series.files) << yaml;
  }
}

TEST(TimeSeries, ScenesPlayOnePassWithoutAnOrbitAndRoundTrip) {
  TempDir t("series-scene");
  writeRawSteps(t);
  const Scene s = scene(t, "  series: {pattern: t%d.raw, first: 0, last: 3}\n" + kRaw, "time: {play: true, mode: swing}\n");
  EXPECT_EQ(s.orbit.frames, 6) << "0 1 2 3 2 1";
  EXPECT_EQ(s.orbit.degrees, 0);
  const Scene again = parseScene(sceneYaml(s), t.path.string(), "again.yaml");
  EXPECT_EQ(sceneYaml(again), sceneYaml(s));
  EXPECT_EQ(again.series, s.series);
  EXPECT_EQ(again.time, s.time);
  const Scene g = parseScene("volume: {generator: {name: moving-blobs, size: 16, steps: 10}}\ntime: {play: true, stride: -2}\n",
                             ".", "g.yaml");
  EXPECT_EQ(g.series.steps, 10);
  EXPECT_EQ(g.orbit.frames, 5);
  EXPECT_EQ(sceneYaml(parseScene(sceneYaml(g), ".", "g2.yaml")), sceneYaml(g));
}

TEST(TimeSeries, BadSeriesAreNamedBeforeTheFirstFrame) {
  TempDir t("series-bad");
  writeRawSteps(t);
  auto has = [&](const std::string& volume, const std::string& rest, const std::string& what) {
    const std::string e = errorOf(t, volume, rest);
    EXPECT_NE(e.find(what), std::string::npos) << e;
  };
  has("  series: {pattern: x%d.raw, first: 0, last: 3}\n" + kRaw, "", "volume.series.pattern: file not found");
  has("  series: {pattern: t%d.raw, first: 0, last: 9}\n" + kRaw, "", "t9.raw (pattern");
  has("  series: {pattern: t%d_%d.raw, first: 0, last: 3}\n" + kRaw, "", "has 2 integer conversions");
  has("  series: {pattern: t%s.raw, first: 0, last: 3}\n" + kRaw, "", "expected one integer conversion");
  has("  series: []\n" + kRaw, "", "volume.series: an empty list");
  has("  series: [t0.raw]\n  file: t0.raw\n" + kRaw, "", "give either file");
  std::ofstream(t.file("back.series")) << R"({"files": [{"name": "t0.raw", "time": 1}, {"name": "t1.raw", "time": 1}]})";
  has("  series: back.series\n" + kRaw, "", "is not after the previous step's");
  std::ofstream(t.file("none.series")) << R"({"files": []})";
  has("  series: none.series\n" + kRaw, "", "the files list is empty");
  // A missing last step of a list or a .series, as of a pattern (found by review: it loaded).
  has("  series: [t0.raw, t1.raw, nothere.raw]\n" + kRaw, "", "volume.series[2]: file not found");
  std::ofstream(t.file("short.series")) << R"({"files": [{"name": "t0.raw", "time": 1}, {"name": "gone.raw", "time": 2}]})";
  has("  series: short.series\n" + kRaw, "", "short.series: files[1]: file not found");
  has("  generator: {name: hollow-shell, steps: 4}\n", "", "'hollow-shell' does not change over time");
  has("  series: [t0.raw, t1.raw]\n" + kRaw, "time: {step: 2}\n", "time.step: must be in 0..1");
  has("  series: [t0.raw, t1.raw]\n" + kRaw, "time: {stride: 0}\n", "time.stride: must not be 0");
  has("  series: [t0.raw, t1.raw]\n" + kRaw, "time: {mode: bounce}\n", "expected loop, once or swing");
  std::filesystem::create_directories(t.path / "slices");
  writeTiffStep((t.path / "slices" / "z0.tif").string(), 0);
  has("  series: [slices, slices]\n", "", "slices: a folder of TIFF slices cannot be a time step");
}

TEST(TimeSeries, AStepThatDiffersOrIsMissingIsNamedWhenRead) {
  TempDir t("series-step-bad");
  writeNifti3d(t.file("a0.nii"), 0);
  writeNifti3d(t.file("a1.nii"), 1, kSz - 1);  // one slice short
  writeNifti3d(t.file("a3.nii"), 3);  // a2.nii is missing
  const Scene s = scene(t, "  series: [a0.nii, a1.nii, a2.nii, a3.nii]\n");
  EXPECT_NO_THROW(loadVolume(s, {{0, 0, 0}, {kSx, kSy, kSz}}, 0));
  try {
    loadVolume(s, {{0, 0, 0}, {kSx, kSy, kSz}}, 1);
    ADD_FAILURE() << "a step of other dims loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("a1.nii: dims [9, 7, 4] differs from step 0's [9, 7, 5]"), std::string::npos)
        << e.what();
  }
  try {
    loadVolume(s, {{0, 0, 0}, {kSx, kSy, kSz}}, 2);
    ADD_FAILURE() << "a missing step loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("a2.nii: file not found"), std::string::npos) << e.what();
  }
  // A raw step cut short is named by the reader with both sizes.
  writeRawSteps(t);
  std::filesystem::resize_file(t.file("t2.raw"), 100);
  const Scene r = scene(t, "  series: {pattern: t%d.raw, first: 0, last: 3}\n" + kRaw);
  try {
    loadVolume(r, {{0, 0, 0}, {kSx, kSy, kSz}}, 2);
    ADD_FAILURE() << "a short step loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("t2.raw: file size is 100 bytes"), std::string::npos) << e.what();
  }
}

// Every step was checked against step 0's header read again from its file, so with that file
// gone (moved, or cleaned up by a simulation) no other step loaded (found by review).
TEST(TimeSeries, AStepLoadsWhenStepZerosFileIsGone) {
  TempDir t("series-step0-gone");
  writeNifti3d(t.file("a0.nii"), 0);
  writeNifti3d(t.file("a1.nii"), 1);
  writeNifti3d(t.file("a2.nii"), 2, kSz - 1);
  const Scene s = scene(t, "  series: [a0.nii, a1.nii, a2.nii]\n");
  std::filesystem::remove(t.file("a0.nii"));
  const VoxelBox box{{0, 0, 0}, {kSx, kSy, kSz}};
  EXPECT_EQ(loadVolume(s, box, 1).values, loadVolume(scene(t, "  series: [a1.nii]\n"), box, 0).values);
  try {
    loadVolume(s, box, 2);
    ADD_FAILURE() << "a step of other dims loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("a2.nii: dims [9, 7, 4] differs from step 0's [9, 7, 5]"), std::string::npos)
        << e.what();
  }
}

// Steps whose headers differ in spacing are refused, unless the scene's volume.spacing
// replaces every step's (found by review: it was refused then too).
TEST(TimeSeries, TheScenesSpacingReplacesStepsHeadersThatDifferInIt) {
  TempDir t("series-spacing");
  writeNifti3d(t.file("a0.nii"), 0);
  writeNifti3d(t.file("a1.nii"), 1, kSz, 0.7);
  const VoxelBox box{{0, 0, 0}, {kSx, kSy, kSz}};
  try {
    loadVolume(scene(t, "  series: [a0.nii, a1.nii]\n"), box, 1);
    ADD_FAILURE() << "a step of other spacing loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("a1.nii: spacing[0] 0.7 differs from step 0's 0.5"), std::string::npos)
        << e.what();
  }
  // One float32 step apart (0.5 and 0.50000006, as tools round a header's pixdim): one
  // spacing, step 0's.
  writeNifti3d(t.file("a2.nii"), 1, kSz, 0.50000006);
  EXPECT_EQ(loadVolume(scene(t, "  series: [a0.nii, a2.nii]\n"), box, 1).spacing, loadVolume(scene(t, "  series: [a0.nii]\n"), box, 0).spacing);
  const Scene given = scene(t, "  series: [a0.nii, a1.nii]\n  spacing: [2, 1, 1]\n");
  const Volume v = loadVolume(given, box, 1);
  EXPECT_EQ(v.spacing, (std::array<double, 3>{2, 1, 1}));
  EXPECT_EQ(v.values, loadVolume(scene(t, "  series: [a1.nii]\n"), box, 0).values);
  // The effective scene (tessera-info prints it) gives spacing only when the scene did:
  // parsed again, it checks the steps as the original does.
  const Scene headers = scene(t, "  series: [a0.nii, a1.nii]\n");
  EXPECT_EQ(sceneYaml(headers).find("spacing:"), std::string::npos) << sceneYaml(headers);
  EXPECT_THROW(loadVolume(parseScene(sceneYaml(headers), t.path.string(), "again.yaml"), box, 1), std::runtime_error);
  EXPECT_NE(sceneYaml(given).find("spacing:"), std::string::npos) << sceneYaml(given);
  EXPECT_NO_THROW(loadVolume(parseScene(sceneYaml(given), t.path.string(), "again.yaml"), box, 1));
}

TEST(TimeSeries, AGeneratedSeriesClosesItsLoop) {
  const Scene g = parseScene("volume: {generator: {name: moving-blobs, size: 16, steps: 8}}\n", ".", "g.yaml");
  const VoxelBox box{{0, 0, 0}, {16, 16, 16}};
  const Volume s0 = loadVolume(g, box, 0), s1 = loadVolume(g, box, 1), s4 = loadVolume(g, box, 4);
  EXPECT_NE(s0.values, s1.values) << "the blobs move";
  EXPECT_NE(s0.values, s4.values);
  // The generator's period is the series: a step past the last would be step 0 again.
  GeneratorSpec spec = std::get<GeneratorSpec>(g.volume);
  spec.time = 1.0;
  const Volume wrapped = generateVolume(spec, box);
  for (size_t i = 0; i < s0.values.size(); ++i) ASSERT_NEAR(wrapped.values[i], s0.values[i], 1e-5) << i;
}

}  // namespace
}  // namespace tessera
