// Helpers for farm tests: a temporary folder with a small scene, running tessera-up on
// the project's compose.yaml with overrides, and comparing frames with tessera-render.
#pragma once
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/image.h"
#include "common/io/image_io.h"
#include "tests/common/image_dump.h"
#include "common/scene.h"

namespace tessera::test {

namespace fs = std::filesystem;

struct CommandResult {
  int exit_code = -1;
  std::string output;
};

// Runs a shell command, bounded by `timeout_s` (coreutils timeout kills it after that).
inline CommandResult runCommand(const std::string& cmd, int timeout_s) {
  std::string full = "timeout -k 5 " + std::to_string(timeout_s) + " " + cmd + " 2>&1";
  CommandResult r;
  FILE* p = popen(full.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// The built-in scene at 64x48 on a 32^3 hollow shell: frames in milliseconds, for farms
// run inside the test process.
inline Scene smallScene(int frames) {
  Scene s = defaultScene();
  s.volume = GeneratorSpec{"hollow-shell", 32, 1};
  s.width = 64;
  s.height = 48;
  s.orbit.frames = frames;
  return s;
}

inline std::string bin(const std::string& name) { return std::string(TESSERA_BINARY_DIR) + "/bin/" + name; }

// The MiB of volume samples each renderer of a farm's output says it read, in order.
inline std::vector<double> renderersRead(const std::string& output) {
  const std::regex line("read ([0-9.]+) MiB of volume samples");
  std::vector<double> mib;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it)
    mib.push_back(std::stod((*it)[1].str()));
  return mib;
}

// Largest difference of any channel, in rgba8 units.
inline int maxAbsDiff(const Image8& a, const Image8& b) {
  if (a.width != b.width || a.height != b.height) return 256;
  int m = 0;
  for (size_t i = 0; i < a.px.size(); ++i) m = std::max(m, std::abs(int(a.px[i]) - int(b.px[i])));
  return m;
}

class FarmDir {
 public:
  explicit FarmDir(const std::string& name) {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("tessera-it-" + name + "-" + std::to_string(getpid()) + "-" + std::to_string(rd() % 100000));
    fs::create_directories(dir_);
  }
  // A failed test keeps its folder (log, frames, and the PNGs of any image mismatch).
  ~FarmDir() {
    if (::testing::Test::HasFailure()) std::fprintf(stderr, "test failed: its files are kept in %s\n", dir_.c_str());
    else if (!getenv("TESSERA_KEEP_TEST_DIRS")) fs::remove_all(dir_);
  }
  const fs::path& path() const { return dir_; }

  // A small scene: hollow shell, odd image size, a short orbit.
  fs::path writeScene(int frames, int size = 40, int w = 97, int h = 83) const {
    fs::path p = dir_ / "scene.yaml";
    std::ofstream(p) << "volume:\n  generator: {name: hollow-shell, size: " << size << ", seed: 1}\n"
                     << "transfer_function:\n  - [0.0, 0.0, 0.0, 0.0, 0.0]\n  - [0.3, 1.0, 0.5, 0.2, 0.05]\n"
                     << "  - [1.0, 1.0, 1.0, 1.0, 0.9]\n"
                     << "camera: {eye: [0.3, 0.5, 2.2], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                     << "image: [" << w << ", " << h << "]\nquality: default\n"
                     << "orbit: {frames: " << frames << ", axis: [0, 1, 0]}\n";
    return p;
  }

  // tessera-up on the project's compose.yaml, sockets and output in this folder.
  // `endpoints` "" = ipc sockets in this folder; "default" = compose.yaml's own. Its output goes to farmLog() as it
  // happens (tests react to what the farm says) and is returned whole.
  CommandResult runFarm(const fs::path& scene, int renderers, int compositors, int frames, int timeout_s = 120,
                        const std::string& extra = "", const std::string& endpoints = "") const {
    // TESSERA_PREMULTIPLIED: the display also writes frame_NNNNNN.pam (exact values to compare).
  std::string cmd = "env TESSERA_PREMULTIPLIED=1 " + bin("tessera-up") + " " + TESSERA_SOURCE_DIR "/compose.yaml" +
                      " --env TESSERA_SCENE=" + scene.string() + " --env TESSERA_RENDERERS=" + std::to_string(renderers) +
                      " --env TESSERA_COMPOSITORS=" + std::to_string(compositors) +
                      " --env TESSERA_FRAMES=" + std::to_string(frames) + " --env TESSERA_OUT=" + (dir_ / "out").string() +
                      (endpoints == "default" ? std::string()
                                              : " --env TESSERA_ENDPOINTS=" +
                                                    (endpoints.empty() ? "ipc://" + (dir_ / "sockets").string() : endpoints)) +
                      " --env TESSERA_WINDOW=off " + extra + " > " + (dir_ / "farm.log").string();
    CommandResult r = runCommand(cmd, timeout_s);
    r.output = farmLog() + r.output;  // r.output: what timeout itself said, if anything
    return r;
  }

  // What the farm of runFarm() has written so far.
  std::string farmLog() const {
    std::ifstream in(dir_ / "farm.log");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  fs::path frame(int k) const {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", k);
    return dir_ / "out" / name;
  }

  // The farm's frame k as the display computed it: premultiplied rgba8, exact (PAM).
  Image8 farmFrame(int k) const {
    fs::path p = frame(k);
    return readPam(p.replace_extension(".pam").string());
  }

  // The one-process render of orbit frame k (bricks = 1: the whole volume at once), as exact
  // premultiplied rgba8: a straight-alpha PNG rounds colour and alpha separately and could
  // add a level of its own. `extra`: more tessera-render options.
  Image8 reference(const fs::path& scene, int k, const std::string& extra = "") const {
    const std::string stem = (dir_ / ("ref_" + std::to_string(k))).string();
    auto r = runCommand(bin("tessera-render") + " " + scene.string() + " --frame " + std::to_string(k) + " -o " +
                            stem + ".png --premultiplied " + stem + ".pam " + extra, 120);
    if (r.exit_code != 0) throw std::runtime_error("tessera-render failed: " + r.output);
    return readPam(stem + ".pam");
  }

  // Whether `actual` is within `tolerance` rgba8 levels of `expected` on every channel. If
  // not, writes <name>_expected.png, <name>_actual.png and <name>_diff.png (the largest
  // channel difference per pixel x 16, opaque grey) into mismatch/ and names them.
  ::testing::AssertionResult matches(const Image8& actual, const Image8& expected, int tolerance,
                                     const std::string& name) const {
    const int diff = maxAbsDiff(actual, expected);
    if (diff <= tolerance) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << name << ": differs by " << diff << " levels (tolerance " << tolerance
                                         << "); see " << writeImageMismatch(dir_ / "mismatch", name, expected, actual);
  }

 private:
  fs::path dir_;
};

// `frames` frames of `scene` on `renderers` + `compositors` compositing by `compositing`: each
// within 1/255 of tessera-render's (the contract) and showing more than `min_area` pixels (else
// it would test nothing). A mismatch is written as `tag`_k images.
inline void expectFarmMatchesRender(FarmDir& dir, const fs::path& scene, int frames, int renderers, int compositors,
                                    const std::string& compositing, int min_area, const std::string& tag) {
  const auto run = dir.runFarm(scene, renderers, compositors, frames, 120, "--env TESSERA_COMPOSITING=" + compositing);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " missing\n" << run.output;
    const Image8 farm = dir.farmFrame(k);
    EXPECT_TRUE(dir.matches(farm, dir.reference(scene, k), 1, tag + "_" + std::to_string(k))) << "frame " << k;
    EXPECT_GT(activeRegion(farm).area(), min_area) << "frame " << k << " is (nearly) empty";
  }
}


}  // namespace tessera::test
