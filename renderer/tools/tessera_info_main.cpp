// tessera-info: what a scene's volume holds before anything renders: dims, type, spacing,
// the data's value range and a histogram (text, and a PNG with --plot), what a renderer
// needs in memory, and the scene with every default filled in.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/bricks.h"
#include "common/image.h"
#include "common/io/image_io.h"
#include "common/scene.h"
#include "common/scene_warnings.h"
#include "common/value_histogram.h"
#include "common/volume_summary.h"
#include "renderer/tools/tool_main.h"

namespace {

using namespace tessera;

// A volume read front to back in slabs of whole planes (about 64 MiB of floats each): the
// tool holds one slab, never the volume, which may be bigger than this machine's memory.
template <class F>
void forEachSlab(const Scene& scene, F&& f) {
  const std::array<int, 3> n = volumeDims(scene);
  const int depth = (int)std::clamp<size_t>((16u << 20) / ((size_t)n[0] * n[1]), 1, (size_t)n[2]);
  VolumeReader reader(scene);
  for (int z = 0; z < n[2]; z += depth) f(reader.read(VoxelBox{{0, 0, z}, {n[0], n[1], std::min(n[2], z + depth)}}));
}

// Equal-width bins over the data's values `data` in file units, `bins` of them and a fine
// 4096 for the suggested range, in one pass. `scene` maps a fixed range (a raw file's: the
// data's own) to 0..1, so each value is found again from its slab's.
std::array<ValueHistogram, 2> histograms(const Scene& scene, std::array<double, 2> data, int bins, bool integral) {
  std::array<ValueHistogram, 2> h{ValueHistogram(data[0], data[1], bins, integral),
                                  ValueHistogram(data[0], data[1], 4096, integral)};
  forEachSlab(scene, [&](const Volume& slab) {
    const double lo = slab.mapped_range[0], span = slab.mapped_range[1] - slab.mapped_range[0];
    for (float x : slab.values) {
      const double raw = lo + x * span;
      h[0].add(raw), h[1].add(raw);
    }
  });
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
  std::printf("# %s renderers\n", line.c_str());
}

void printHistogram(const ValueHistogram& h) {
  const uint64_t peak = *std::max_element(h.counts.begin(), h.counts.end());
  std::printf("# histogram (%zu bins; bars on a log scale):\n", h.counts.size());
  const int d = digitsToTell(h.edge(0), h.edge(1), 6), w = std::max(12, d + 6);  // edges told apart
  for (size_t b = 0; b < h.counts.size(); ++b) {
    const int bar = h.counts[b] ? (int)std::lround(40 * std::log1p((double)h.counts[b]) / std::log1p((double)peak)) : 0;
    std::printf("#   %*.*g .. %-*.*g %12llu %s\n", w, d, h.edge(b), w, d, h.edge(b + 1),
                (unsigned long long)h.counts[b], std::string(bar, '#').c_str());
  }
}

// Bars on a log scale, 4 pixels a bin, on a dark background.
void plotHistogram(const ValueHistogram& h, const std::string& path) {
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
                 "scene file, or a NIfTI/NRRD/TIFF volume file, a DICOM series' or a TIFF stack's folder (read as the scene 'volume: {file: F}'); "
                 "default: the built-in scene");
  app.add_option("--bins", bins, "histogram bins")->check(CLI::Range(1, 4096))->capture_default_str();
  app.add_option("--plot", plot, "also write the histogram as a PNG");
  CLI11_PARSE(app, argc, argv);
  Scene scene = scene_path.empty() ? defaultScene() : loadScene(scene_path);
  // All but the scene is YAML comments: the output saved as a file is that scene.
  std::printf("# scene %s, every default filled in\n%s\n", scene_path.empty() ? "(built-in)" : scene_path.c_str(),
              sceneYaml(scene).c_str());
  if (!scene.has_volume) return 0;
  // Over the data's own range, so a narrower `range` clips nothing of the histogram: a raw
  // file's is streamed once for its min..max, a generator's values are found slab by slab.
  Scene unclipped = scene;
  const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume);
  if (auto* r = std::get_if<RawVolumeSpec>(&unclipped.volume)) r->has_range = false;
  Volume shape;
  shape.spacing = raw ? raw->spacing : std::get<GeneratorSpec>(scene.volume).spacing;
  shape.data_range = fixVolumeRange(unclipped);
  if (!raw) {
    shape.data_range = {INFINITY, -INFINITY};
    forEachSlab(unclipped, [&](const Volume& slab) {
      shape.data_range = {std::min(shape.data_range[0], slab.data_range[0]), std::max(shape.data_range[1], slab.data_range[1])};
    });
  }
  shape.dims = volumeDims(scene);
  shape.mapped_range = raw && raw->has_range ? raw->range : raw ? shape.data_range : std::array<double, 2>{0, 1};
  std::printf("# volume: %d x %d x %d voxels, %s, spacing %g %g %g\n", shape.dims[0], shape.dims[1], shape.dims[2],
              raw ? voxelTypeName(raw->type) : "generated (float)", shape.spacing[0], shape.spacing[1], shape.spacing[2]);
  const int dv = digitsToTell(shape.data_range[0], shape.data_range[1]);
  const int dm = digitsToTell(shape.mapped_range[0], shape.mapped_range[1]);
  std::printf("# values: %.*g .. %.*g; mapped to the transfer function: %.*g .. %.*g%s\n", dv, shape.data_range[0], dv,
              shape.data_range[1], dm, shape.mapped_range[0], dm, shape.mapped_range[1],
              raw && !raw->has_range ? " (no range given: the data's own)" : "");
  if (scene.window) {
    const int dw = digitsToTell(scene.window->lo(), scene.window->hi());
    std::printf("# window: the colour map spans the values %.*g .. %.*g\n", dw, scene.window->lo(), dw, scene.window->hi());
  }
  if (!scene.crop.whole()) {
    const VoxelBox c = cropBox(scene.crop, shape.dims);
    std::printf("# crop: voxels [%d, %d) x [%d, %d) x [%d, %d) are rendered, %d x %d x %d of them\n", c.lo[0], c.hi[0],
                c.lo[1], c.hi[1], c.lo[2], c.hi[2], c.hi[0] - c.lo[0], c.hi[1] - c.lo[1], c.hi[2] - c.lo[2]);
  }
  if (scene.series.steps > 1)
    std::printf("# time steps: %d; the values, warnings and histogram here are step 0's, and so is the range every step "
                "is mapped with unless the scene gives `range`\n",
                scene.series.steps);
  for (const std::string& w : volumeWarnings(scene, shape)) std::printf("# warning: %s\n", w.c_str());
  const bool integral = raw && storesIntegers(*raw);
  const auto [h, fine] = histograms(unclipped, shape.data_range, bins, integral);
  if (std::string advice = rangeSuggestion(scene, fine); !advice.empty()) std::printf("# warning: %s\n", advice.c_str());
  printHistogram(h);
  if (!plot.empty()) {
    plotHistogram(h, plot);
    std::printf("# wrote %s\n", plot.c_str());
  }
  printRendererMemory(shape.dims, scene.shading.on);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-info", [&] { return run(argc, argv); });
}
