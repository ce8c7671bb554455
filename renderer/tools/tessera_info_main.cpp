// tessera-info: what a scene's volume holds before anything renders: dims, type, spacing,
// the data's value range and a histogram (text, and a PNG with --plot), what a renderer
// needs in memory, and the scene with every default filled in.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <cstdio>
#include <string>
#include <vector>

#include "common/bricks.h"
#include "common/image.h"
#include "common/io/image_io.h"
#include "common/scene.h"
#include "renderer/tools/tool_main.h"

namespace {

using namespace tessera;

// Files whose header says what they hold: a scene of one line is all they need.
bool isVolumeFile(const std::string& path) {
  std::string p = path;
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  for (const char* ext : {".nii", ".nii.gz", ".hdr", ".nrrd", ".nhdr"})
    if (p.size() >= std::strlen(ext) && p.compare(p.size() - std::strlen(ext), std::string::npos, ext) == 0) return true;
  return false;
}

Scene volumeScene(const std::string& path) {
  const std::filesystem::path abs = std::filesystem::absolute(path);
  return parseScene("volume: {file: " + nlohmann::json(abs.filename().string()).dump() + "}\n", abs.parent_path().string(),
                    path);
}

struct Histogram {
  double lo = 0, hi = 0;          // in the file's units
  std::vector<uint64_t> counts;   // equal-width bins over [lo, hi]; the last includes hi
};

// Over the data's own values in file units; `v` must be normalised over its own range.
Histogram histogram(const Volume& v, int bins) {
  Histogram h{v.data_range[0], v.data_range[1], std::vector<uint64_t>(bins, 0)};
  const double lo = v.data_range[0], span = v.data_range[1] - v.data_range[0];
  const double width = (h.hi - h.lo) / bins;
  for (float x : v.values) {
    const double raw = lo + x * span;
    const int b = width > 0 ? (int)std::floor((raw - h.lo) / width) : 0;
    ++h.counts[std::clamp(b, 0, bins - 1)];
  }
  return h;
}

std::string bytesText(double bytes) {
  const int unit = bytes < (1 << 20) ? 10 : bytes < (1 << 30) ? 20 : 30;
  char b[48];
  std::snprintf(b, sizeof b, "%.1f %s", bytes / (double)(1ull << unit), unit == 10 ? "KiB" : unit == 20 ? "MiB" : "GiB");
  return b;
}

// A renderer holds its bricks and one ghost voxel around them: float values, 16-bit
// quantized values and the min-max hierarchy, about 6 bytes a voxel; with shading two ghost
// voxels and 8 bytes more for the gradients. Bricks of an even split (the farm balances by
// visible content, so its largest brick may be bigger).
void printRendererMemory(const std::array<int, 3>& dims, bool shaded) {
  const int ghost = shaded ? 2 : 1, per_voxel = shaded ? 14 : 6;
  std::string line = "memory per renderer (bricks + ghost voxels, about " + std::to_string(per_voxel) +
                     " bytes a voxel" + (shaded ? " with shading" : "") + "):";
  for (int n : {1, 2, 4, 8}) {
    size_t most = 0;
    for (const BrickBox& b : splitMask(dims, nullptr, n).bricks) {
      size_t voxels = 1;
      for (int a = 0; a < 3; ++a) voxels *= (size_t)(std::min(dims[a], b.hi[a] + ghost) - std::max(0, b.lo[a] - ghost));
      most = std::max(most, voxels);
    }
    line += " " + bytesText((double)per_voxel * (double)most) + " for " + std::to_string(n) + (n < 8 ? "," : "");
  }
  std::printf("%s renderers\n", line.c_str());
}

void printHistogram(const Histogram& h) {
  const uint64_t peak = *std::max_element(h.counts.begin(), h.counts.end());
  const double width = (h.hi - h.lo) / h.counts.size();
  std::printf("histogram (%zu bins; bars on a log scale):\n", h.counts.size());
  for (size_t b = 0; b < h.counts.size(); ++b) {
    const int bar = h.counts[b] ? (int)std::lround(40 * std::log1p((double)h.counts[b]) / std::log1p((double)peak)) : 0;
    std::printf("  %12.6g .. %-12.6g %12llu %s\n", h.lo + b * width, h.lo + (b + 1) * width,
                (unsigned long long)h.counts[b], std::string(bar, '#').c_str());
  }
}

// Bars on a log scale, 4 pixels a bin, on a dark background.
void plotHistogram(const Histogram& h, const std::string& path) {
  const int bar_w = 4, height = 200, width = bar_w * (int)h.counts.size();
  Image8 img(width, height);
  const double peak = std::log1p((double)*std::max_element(h.counts.begin(), h.counts.end()));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double level = std::log1p((double)h.counts[x / bar_w]) / peak;
      const bool bar = height - 1 - y < level * (height - 1) && x % bar_w != bar_w - 1;
      uint8_t* p = img.at(x, y);
      p[0] = bar ? 230 : 24, p[1] = bar ? 150 : 24, p[2] = bar ? 60 : 28, p[3] = 255;
    }
  writePng(path, img);
}

int run(int argc, char** argv) {
  CLI::App app{"tessera-info: a scene's volume (dims, type, value range, histogram, memory) and the scene "
               "with every default filled in"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  std::string scene_path, plot;
  int bins = 16;
  app.add_option("scene", scene_path,
                 "scene file, or a NIfTI/NRRD volume file (read as the scene 'volume: {file: F}'); default: the built-in scene");
  app.add_option("--bins", bins, "histogram bins")->check(CLI::Range(1, 4096))->capture_default_str();
  app.add_option("--plot", plot, "also write the histogram as a PNG");
  CLI11_PARSE(app, argc, argv);
  Scene scene = scene_path.empty() ? defaultScene() : isVolumeFile(scene_path) ? volumeScene(scene_path) : loadScene(scene_path);
  std::printf("# scene %s, every default filled in\n%s\n", scene_path.empty() ? "(built-in)" : scene_path.c_str(),
              sceneYaml(scene).c_str());
  if (!scene.has_volume) return 0;
  // Loaded over the data's own range, so a narrower `range` clips nothing of the histogram.
  Scene unclipped = scene;
  if (auto* r = std::get_if<RawVolumeSpec>(&unclipped.volume)) r->has_range = false;
  Volume v = loadVolume(unclipped);
  const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume);
  if (raw && raw->has_range) v.mapped_range = raw->range;
  std::printf("volume: %d x %d x %d voxels, %s, spacing %g %g %g\n", v.dims[0], v.dims[1], v.dims[2],
              raw ? voxelTypeName(raw->type)
                  : "generated (float)",
              v.spacing[0], v.spacing[1], v.spacing[2]);
  std::printf("values: %.9g .. %.9g; mapped to the transfer function: %.9g .. %.9g%s\n", v.data_range[0],
              v.data_range[1], v.mapped_range[0], v.mapped_range[1],
              raw && !raw->has_range ? " (no range given: the data's own)" : "");
  if (std::string why = rangeProblem(v); !why.empty()) std::printf("warning: %s\n", why.c_str());
  const Histogram h = histogram(v, bins);
  printHistogram(h);
  if (!plot.empty()) {
    plotHistogram(h, plot);
    std::printf("wrote %s\n", plot.c_str());
  }
  printRendererMemory(v.dims, scene.shading.on);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-info", [&] { return run(argc, argv); });
}
