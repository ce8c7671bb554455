// A scientist's first volume: a scene of three lines renders the data with the default
// colour map over the data's own values and a fitted camera; a range that misses the data
// is said; tessera-info reports the values exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

// A 32^3 uint16 ball: 1000 at the centre falling to 0 at radius 12 voxels, 0 outside; the
// values run 0..1000, far below the type's 65535.
fs::path writeBall(const FarmDir& dir) {
  const int n = 32;
  std::vector<uint16_t> v((size_t)n * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double r = std::sqrt(std::pow(x - 16, 2) + std::pow(y - 16, 2) + std::pow(z - 16, 2));
        v[x + n * (y + (size_t)n * z)] = (uint16_t)std::lround(std::max(0.0, 1000 * (1 - r / 12)));
      }
  const fs::path p = dir.path() / "ball.raw";
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(v.data()), (std::streamsize)(v.size() * 2));
  return p;
}

fs::path writeSceneFile(const FarmDir& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir.path() / name;
  std::ofstream(p) << text;
  return p;
}

TEST(FirstContact, AThreeLineSceneRendersTheDataOverItsOwnRange) {
  FarmDir dir("three-lines");
  writeBall(dir);
  const auto scene = writeSceneFile(dir, "ball.yaml", "volume: {file: ball.raw, dims: [32, 32, 32], type: uint16}\n");
  const std::string pam = (dir.path() / "ball.pam").string();
  const auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --image 96x96 -o " +
                                (dir.path() / "ball.png").string() + " --premultiplied " + pam,
                            120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  const Image8 img = readPam(pam);
  // The ball fills the middle of the fitted view; its rim (low values) is cool, its core
  // (high values) warm: the colour map spans the data, not 0..65535.
  int visible = 0, cool = 0, warm = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* p = img.at(x, y);
      if (p[3] < 8) continue;
      ++visible;
      cool += p[2] > p[0] + 8;
      warm += p[0] > p[2] + 8;
    }
  EXPECT_GT(visible, img.width * img.height / 10) << "the ball covers too little of the image";
  EXPECT_GT(cool, 0) << "no pixel shows the low end of the colour map";
  EXPECT_GT(warm, 0) << "no pixel shows the high end of the colour map";
  EXPECT_EQ(img.at(0, 0)[3], 0) << "the fitted view should leave the corners empty";
}

// A file without `range` on the farm: the master streams it once for its min..max and tells
// the renderers, which read only their bricks (they used to stream the whole file each), and
// the frame is tessera-render's (which scans the file itself) within the contract's 1/255.
TEST(FirstContact, OnTheFarmEachRendererReadsOnlyItsBricksOfAFileWithoutRange) {
  FarmDir dir("own-range-farm");
  const int n = 128;  // 4 MiB of uint16
  std::vector<uint16_t> v((size_t)n * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double r = std::sqrt(std::pow(x - 64, 2) + std::pow(y - 60, 2) + std::pow(z - 70, 2));
        v[x + n * (y + (size_t)n * z)] = (uint16_t)std::lround(std::max(0.0, 1000 * (1 - r / 50)) + 3);
      }
  std::ofstream(dir.path() / "b.raw", std::ios::binary)
      .write(reinterpret_cast<const char*>(v.data()), (std::streamsize)(v.size() * 2));
  const auto scene = writeSceneFile(dir, "b.yaml",
                                    "volume: {file: b.raw, dims: [128, 128, 128], type: uint16}\nimage: [64, 48]\n"
                                    "camera: {eye: [0.4, 0.6, 2.0], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n");
  const auto r = dir.runFarm(scene, 2, 1, 1);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(dir.matches(dir.farmFrame(0), dir.reference(scene, 0), 1, "own_range"));
  const std::vector<double> read = renderersRead(r.output);
  EXPECT_EQ(read.size(), 2u) << r.output;
  for (double mib : read) {
    EXPECT_GT(mib, 1.5) << "half the file is a renderer's bricks\n" << r.output;
    EXPECT_LT(mib, 2.5) << "a renderer read more than its bricks and ghost voxels of the 4 MiB file\n" << r.output;
  }
}

// The camera fitted when the scene has none fits the image asked for: a tall one
// (`--image 40x200` on a scene of the default square image) shows the whole box, an opaque
// one here, with transparent pixels down both sides.
TEST(FirstContact, TheFittedCameraFitsATallImageToo) {
  FarmDir dir("tall");
  std::vector<uint16_t> v(8 * 8 * 8);
  for (size_t i = 0; i < v.size(); ++i) v[i] = (uint16_t)(500 + 60 * (i % 8));
  std::ofstream(dir.path() / "box.raw", std::ios::binary)
      .write(reinterpret_cast<const char*>(v.data()), (std::streamsize)(v.size() * 2));
  const auto scene = writeSceneFile(dir, "box.yaml",
                                    "volume: {file: box.raw, dims: [8, 8, 8], type: uint16}\n"
                                    "transfer_function: [[0, 1, 1, 1, 1], [1, 1, 1, 1, 1]]\n");
  const std::string pam = (dir.path() / "box.pam").string();
  const auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --image 40x200 -o " +
                                (dir.path() / "box.png").string() + " --premultiplied " + pam,
                            120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image8 img = readPam(pam);
  ASSERT_EQ(img.width, 40);
  int lo_x = 40, hi_x = -1;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.at(x, y)[3] > 0) lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
  EXPECT_GT(lo_x, 0) << "the box reaches the left edge: cut";
  EXPECT_LT(hi_x, 39) << "the box reaches the right edge: cut";
  EXPECT_GT(hi_x - lo_x, 20) << "the box fills most of the width";
}

TEST(FirstContact, ARangeOutsideTheDataIsSaidWithTheDataValues) {
  FarmDir dir("bad-range");
  writeBall(dir);
  const auto scene = writeSceneFile(dir, "ball.yaml",
                                    "volume: {file: ball.raw, dims: [32, 32, 32], type: uint16, range: [5000, 6000]}\n");
  const auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --image 32x32 -o " +
                                (dir.path() / "ball.png").string(),
                            120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ball.yaml: volume.range: range [5000, 6000] lies above every value (the data's values "
                          "run 0 .. 1000)"),
            std::string::npos)
      << r.output;
}

// A `window` beside every value is said by tessera-render; with --window in its place, not.
TEST(FirstContact, AWindowBesideTheDataIsSaidUnlessReplaced) {
  FarmDir dir("bad-window");
  writeBall(dir);
  const auto scene = writeSceneFile(dir, "ball.yaml",
                                    "volume: {file: ball.raw, dims: [32, 32, 32], type: uint16}\n"
                                    "window: {level: 3000, width: 400}\n");
  const std::string render = bin("tessera-render") + " " + scene.string() + " --image 32x32 -o " + (dir.path() / "ball.png").string();
  const auto r = runCommand(render, 120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ball.yaml: window: level 3000, width 400 spans 2800 .. 3200, none of the volume's values 0 .. 1000"),
            std::string::npos)
      << r.output;
  const auto replaced = runCommand(render + " --window 0.5,1", 120);
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_EQ(replaced.output.find("window:"), std::string::npos) << replaced.output;
}

TEST(FirstContact, AFarmWhoseFramesShowNothingSaysSoOnce) {
  FarmDir dir("looking-away");
  const auto scene = writeSceneFile(dir, "away.yaml",
                                    "volume: {generator: {name: hollow-shell, size: 24}}\n"
                                    "camera: {eye: [0, 0, 3], target: [0, 0, 6]}\nimage: [48, 32]\n"
                                    "orbit: {frames: 4, axis: [0, 0, 1]}\n");
  // Binary swap too: there no compositor takes part, the renderers' images say it.
  for (const char* compositing : {"direct-send", "binary-swap"}) {
    const auto r = dir.runFarm(scene, 2, 1, 4, 120, std::string("--env TESSERA_COMPOSITING=") + compositing);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string warning = "has no visible pixel: is the camera looking at the volume";
    const size_t at = r.output.find(warning);
    EXPECT_NE(at, std::string::npos) << compositing << "\n" << r.output;
    EXPECT_EQ(r.output.find(warning, at + 1), std::string::npos) << "said more than once\n" << r.output;
  }
}

// No compositor: fine for binary swap (the renderers send the display their bands, checked in
// farm_test.cpp), refused at start for direct send, with what to change.
TEST(FirstContact, NoCompositorIsRefusedUnlessTheFarmSwaps) {
  FarmDir dir("no-compositor");
  const auto scene = dir.writeScene(2);
  const auto r = dir.runFarm(scene, 2, 0, 2, 60, "--env TESSERA_COMPOSITING=direct-send");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("TESSERA_COMPOSITORS=0: only binary swap"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("composites by direct send: give it at least one compositor"), std::string::npos) << r.output;
}

TEST(FirstContact, AStaticViewIsRenderedOnceAndTheOtherFramesSaySo) {
  FarmDir dir("static-view");
  const auto scene =
      writeSceneFile(dir, "still.yaml", "volume: {generator: {name: hollow-shell, size: 24}}\nimage: [48, 32]\n");
  const auto r = dir.runFarm(scene, 2, 1, 4);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir.path() / "out" / "metrics.jsonl");
  std::vector<nlohmann::json> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(nlohmann::json::parse(l));
  ASSERT_EQ(lines.size(), 4u) << r.output;
  for (const auto& j : lines) {
    const bool first = j["frame"] == 0;
    EXPECT_EQ(j["rerendered"], first) << j.dump();
    EXPECT_EQ(j.contains("render_ms_max"), first) << "a reused image has no render time\n" << j.dump();
    EXPECT_EQ(j["render_images_made"], first ? 2 : 0) << j.dump();
    EXPECT_EQ(j["render_images_reused"], first ? 0 : 2) << j.dump();
    EXPECT_FALSE(j.contains("overlap_factor")) << "a sort-first field in a sort-last frame\n" << j.dump();
  }
  EXPECT_NE(r.output.find("(3 of 4 frames reused the image: the view did not change)"), std::string::npos) << r.output;
  // Every field a line carries is explained in docs/metrics.md.
  std::ifstream doc_in(std::string(TESSERA_SOURCE_DIR) + "/docs/metrics.md");
  const std::string doc(std::istreambuf_iterator<char>(doc_in), {});
  for (const auto& j : lines)
    for (const auto& [key, value] : j.items()) EXPECT_NE(doc.find("`" + key + "`"), std::string::npos) << key;
}

// An interactive run without a window renders its first frame and says how to steer or stop it.
TEST(FirstContact, AnInteractiveRunWithoutAWindowSaysHowToSteerAndStopIt) {
  FarmDir dir("interactive-nowindow");
  const auto scene =
      writeSceneFile(dir, "still.yaml", "volume: {generator: {name: hollow-shell, size: 24}}\nimage: [48, 32]\n");
  const auto r = dir.runFarm(scene, 1, 1, 0, 8);  // runs until stopped: timeout ends it
  EXPECT_NE(r.output.find("without either only the first frame is rendered"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Ctrl-C or closing the window stops it"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir.frame(0))) << r.output;
  EXPECT_FALSE(fs::exists(dir.frame(1))) << "a frame without input";
}

// The counts of tessera-info's histogram lines ("lo .. hi count bar"), in order.
std::vector<unsigned long long> histogramCounts(const std::string& output) {
  std::vector<unsigned long long> counts;
  std::istringstream in(output);
  for (std::string l; std::getline(in, l);) {
    double a, b;
    unsigned long long c;
    if (std::sscanf(l.c_str(), "# %lf .. %lf %llu", &a, &b, &c) == 3) counts.push_back(c);
  }
  return counts;
}

TEST(FirstContact, TesseraInfoReportsTheValuesAndTheirHistogramExactly) {
  FarmDir dir("info");
  std::vector<uint8_t> v(8 * 8 * 8, 0);  // 256 voxels of 0, 192 of 100, 64 of 200
  for (size_t i = 256; i < 448; ++i) v[i] = 100;
  for (size_t i = 448; i < 512; ++i) v[i] = 200;
  std::ofstream(dir.path() / "k.raw", std::ios::binary).write(reinterpret_cast<const char*>(v.data()), 512);
  const auto scene = writeSceneFile(dir, "k.yaml", "volume: {file: k.raw, dims: [8, 8, 8], type: uint8}\n");
  const std::string png = (dir.path() / "hist.png").string();
  const auto r = runCommand(bin("tessera-info") + " " + scene.string() + " --bins 4 --plot " + png, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("volume: 8 x 8 x 8 voxels, uint8"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("values: 0 .. 200; mapped to the transfer function: 0 .. 200 (no range given"),
            std::string::npos)
      << r.output;
  // Bins of width 50 over 0..200 (the last one includes 200).
  for (const char* line : {"0 .. 50", "50 .. 100", "100 .. 150", "150 .. 200"}) {
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;
  }
  const std::vector<unsigned long long> counts = histogramCounts(r.output);
  EXPECT_EQ(counts, (std::vector<unsigned long long>{256, 0, 192, 64})) << r.output;
  EXPECT_NE(r.output.find("transfer_function:"), std::string::npos) << "the effective scene is missing\n" << r.output;
  EXPECT_NE(r.output.find("camera:"), std::string::npos) << r.output;
  // Saved, the output is the scene: the rest is comments.
  std::ofstream(dir.path() / "again.yaml") << r.output;
  const Scene again = loadScene((dir.path() / "again.yaml").string());
  EXPECT_EQ(sceneYaml(again), sceneYaml(loadScene(scene.string()))) << r.output;
  const Image8 plot = readPng(png);
  EXPECT_EQ(plot.width, 16);

  // The same voxels as a NIfTI-1 file, given to tessera-info alone (its header says the rest).
  std::vector<char> nii(352, 0);
  auto put = [&](size_t at, auto value) { std::memcpy(nii.data() + at, &value, sizeof value); };
  put(0, int32_t{348});
  for (int i = 0; i < 8; ++i) put(40 + 2 * i, int16_t(i == 0 ? 3 : i <= 3 ? 8 : 1));  // dim
  put(70, int16_t{2});                                                                 // uint8
  put(72, int16_t{8});
  for (int i = 0; i < 8; ++i) put(76 + 4 * i, 1.0f);  // pixdim
  put(108, 352.0f);                                   // vox_offset
  std::memcpy(nii.data() + 344, "n+1", 4);
  nii.insert(nii.end(), v.begin(), v.end());
  std::ofstream(dir.path() / "k.nii", std::ios::binary).write(nii.data(), (std::streamsize)nii.size());
  const auto n = runCommand(bin("tessera-info") + " " + (dir.path() / "k.nii").string() + " --bins 4", 60);
  ASSERT_EQ(n.exit_code, 0) << n.output;
  EXPECT_NE(n.output.find("volume: 8 x 8 x 8 voxels, uint8"), std::string::npos) << n.output;
  const std::vector<unsigned long long> from_nifti = histogramCounts(n.output);
  EXPECT_EQ(from_nifti, counts) << n.output;
  // And as a .hdr + .img pair named by its image (tessera-info took a .img for a scene file).
  std::vector<char> hdr(nii.begin(), nii.begin() + 348);
  std::memcpy(hdr.data() + 108, "\0\0\0\0", 4);  // vox_offset 0
  std::memcpy(hdr.data() + 344, "ni1", 4);
  std::ofstream(dir.path() / "p.hdr", std::ios::binary).write(hdr.data(), (std::streamsize)hdr.size());
  std::ofstream(dir.path() / "p.img", std::ios::binary).write(reinterpret_cast<const char*>(v.data()), (std::streamsize)v.size());
  const auto pair = runCommand(bin("tessera-info") + " " + (dir.path() / "p.img").string() + " --bins 4", 60);
  ASSERT_EQ(pair.exit_code, 0) << pair.output;
  EXPECT_EQ(histogramCounts(pair.output), counts) << pair.output;
}

// tessera-info streams the volume in slabs (found by review: it loaded the whole volume, so
// a scientist's first look at a file bigger than memory failed there). Here 512 MiB of
// float samples under an address-space limit of 256 MiB: one voxel of 200 in zeros.
TEST(FirstContact, TesseraInfoReadsAVolumeBiggerThanItsMemoryInSlabs) {
  FarmDir dir("info-big");
  const auto raw = dir.path() / "big.raw";
  {
    std::ofstream f(raw, std::ios::binary);
    f.seekp(1000);
    f.put((char)200);
  }
  std::filesystem::resize_file(raw, 512ull * 512 * 512);  // sparse: no disk for the zeros
  const auto scene = writeSceneFile(dir, "big.yaml", "volume: {file: big.raw, dims: [512, 512, 512], type: uint8}\n");
  const auto r = runCommand("prlimit --as=" + std::to_string(256 << 20) + " " + bin("tessera-info") + " " + scene.string() +
                                " --bins 2",
                            120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("values: 0 .. 200;"), std::string::npos) << r.output;
  const std::vector<unsigned long long> counts = histogramCounts(r.output);
  EXPECT_EQ(counts, (std::vector<unsigned long long>{512ull * 512 * 512 - 1, 1})) << r.output;
}

// tessera-info's other volumes: a generator's values are its own (no file units to map them
// back to), a constant file is said, and a scene's range maps the colours, not the histogram.
TEST(FirstContact, TesseraInfoOnAGeneratorAConstantFileAndADeclaredRange) {
  FarmDir dir("info-kinds");
  const auto gen = writeSceneFile(dir, "g.yaml", "volume: {generator: {name: head, size: 16}}\n");
  const auto g = runCommand(bin("tessera-info") + " " + gen.string() + " --bins 4", 60);
  ASSERT_EQ(g.exit_code, 0) << g.output;
  const Volume v = generateVolume(GeneratorSpec{"head", 16, 1});
  const auto [lo, hi] = std::minmax_element(v.values.begin(), v.values.end());
  const double width = ((double)*hi - *lo) / 4;
  std::vector<unsigned long long> expected(4, 0);
  for (float x : v.values) ++expected[std::clamp((int)std::floor((x - (double)*lo) / width), 0, 3)];
  EXPECT_EQ(histogramCounts(g.output), expected) << g.output;
  EXPECT_NE(g.output.find("mapped to the transfer function: 0 .. 1\n"), std::string::npos) << g.output;
  EXPECT_EQ(g.output.find("# crop:"), std::string::npos) << "no crop: nothing said of one";
  const auto cut = writeSceneFile(dir, "cut.yaml", "volume: {generator: {name: head, size: 16}}\ncrop: {x: [0, 0.5], z: [0.25, 1]}\n"
                                                  "window: {level: 0.5, width: 0.25}\n");
  const auto cropped = runCommand(bin("tessera-info") + " " + cut.string() + " --bins 4", 60);
  ASSERT_EQ(cropped.exit_code, 0) << cropped.output;
  EXPECT_NE(cropped.output.find("# crop: voxels [0, 8) x [0, 16) x [4, 16) are rendered, 8 x 16 x 12 of them\n"),
            std::string::npos) << cropped.output;
  EXPECT_NE(cropped.output.find("# window: the colour map spans the values 0.375 .. 0.625\n"), std::string::npos)
      << cropped.output;

  std::ofstream(dir.path() / "c.raw", std::ios::binary) << std::string(64, (char)7);
  const auto c = runCommand(bin("tessera-info") + " " +
                                writeSceneFile(dir, "c.yaml", "volume: {file: c.raw, dims: [4, 4, 4], type: uint8}\n").string() +
                                " --bins 2",
                            60);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("values: 7 .. 7;"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("c.yaml: volume: every voxel has the value 7"), std::string::npos) << c.output;
  EXPECT_EQ(histogramCounts(c.output), (std::vector<unsigned long long>{64, 0})) << c.output;

  std::vector<uint8_t> k(8 * 8 * 8, 0);  // as in TesseraInfoReportsTheValuesAndTheirHistogramExactly
  std::fill(k.begin() + 256, k.begin() + 448, 100);
  std::fill(k.begin() + 448, k.end(), 200);
  std::ofstream(dir.path() / "k.raw", std::ios::binary).write(reinterpret_cast<const char*>(k.data()), 512);
  const auto r = runCommand(
      bin("tessera-info") + " " +
          writeSceneFile(dir, "k.yaml", "volume: {file: k.raw, dims: [8, 8, 8], type: uint8, range: [50, 150]}\n").string() +
          " --bins 4",
      60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("values: 0 .. 200; mapped to the transfer function: 50 .. 150\n"), std::string::npos) << r.output;
  EXPECT_EQ(histogramCounts(r.output), (std::vector<unsigned long long>{256, 0, 192, 64})) << r.output;
}

}  // namespace
}  // namespace tessera::test
