// tessera-render: renders a scene in one process with the CPU ray caster or the GLSL
// (OSMesa) backend, optionally split into bricks and composited exactly as the farm does,
// and writes a PNG (and a premultiplied rgba8 PAM, raw float).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ctime>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "renderer/tools/tool_main.h"
#include "common/bricks.h"
#include "common/clock.h"
#include "common/cpu.h"
#include "common/io/image_io.h"
#include "common/max_intensity.h"
#include "common/scene.h"
#include "common/scene_warnings.h"
#include "common/volume_summary.h"
#include "renderer/volume/backend.h"
#include "renderer/tools/mesh_render_tool.h"

namespace {

using namespace tessera;

void parseSize(const std::string& s, int& w, int& h) {
  char x = 0;
  int a = 0, b = 0;
  char rest = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &a, &x, &b, &rest) != 3 || (x != 'x' && x != 'X') || a <= 0 || b <= 0 ||
      a > 16384 || b > 16384)
    throw std::invalid_argument("--image: expected WxH with 1..16384 each, got '" + s + "'");
  w = a;
  h = b;
}

// Renders the scene whole (one brick) or as the bricks of `tree` composited in visibility
// order, as the farm does; `stats` (may be null) receives the sample counts, `drawn` the
// rectangle outside which the image is transparent. `recycled`: the image before, transparent
// (ImageF::clear), whose memory this one takes, as a renderer's frames do: fresh pages for a
// 1024^2 image were ~9 ms of a ~150 ms frame here, which a frame in a running farm, or in
// VTK's window, does not pay. `mip` (blend: maximum or minimum): the bricks' value pixels are merged by
// their maxima and mapped once, as the farm's compositors do.
ImageF renderScene(const renderer::VolumeBackend& rc, const Volume& vol, const BrickTree& tree, const Camera& cam,
                   int w, int h, const renderer::RenderOptions& opt, renderer::RenderStats* stats, const MaxIntensity* mip,
                   Rect* drawn = nullptr, ImageF recycled = {}) {
  auto mapped = [&](ImageF img, const Rect& r) {
    if (mip)
      for (int y = r.y; y < r.y + r.h; ++y) mip->map(img.at(r.x, y), (size_t)r.w);
    return img;
  };
  if (tree.bricks.size() <= 1) {
    Rect r;
    ImageF img = rc.render(cam, w, h, renderer::wholeVolume(vol), opt, stats, &r, std::move(recycled));
    if (drawn) *drawn = r;
    return mapped(std::move(img), r);
  }
  ImageF out = renderer::takeRecycled(w, h, std::move(recycled)), part;
  Rect all;
  for (int leaf : tree.visibilityOrder(vol, cam)) {
    renderer::RenderStats s;
    Rect active;
    part = rc.render(cam, w, h, tree.bricks[leaf], opt, stats ? &s : nullptr, &active, std::move(part));
    if (!active.empty()) mip ? compositeMaximum(out, part, active) : compositeOver(out, part, active);
    part.clear(active);  // transparent again for the next brick
    all = unite(all, active);
    if (stats) *stats += s;
  }
  if (drawn) *drawn = all;
  return mapped(std::move(out), all);
}

struct Args {
  std::string scene_path, out = "out.png", quality_name, size, raw, pam, backend = "cpu";
  std::vector<double> background, window;
  int bricks = 1, frame = 0, threads = 0, repeat = 1, step = -1;
  bool print_stats = false, compare_ref = false, no_skip = false;
  // Mesh scenes (OSMesa): tiles, anti-aliasing overrides and the anti-aliasing sweep.
  std::string tiles = "1x1", aa;
  int aa_samples = 0;
  bool aa_sweep = false;
};

void addOptions(CLI::App& app, Args& a) {
  app.add_option("scene", a.scene_path, "scene file (default: the built-in hollow shell)");
  // The extension says the format: only PNG is written, so any other is refused by name
  // rather than writing PNG bytes into a file called .jpg.
  app.add_option("-o,--output", a.out, "output PNG (.png)")->capture_default_str()->check([](const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    return ext == ".png" || ext == ".PNG" ? std::string()
                                          : "'" + path + "': tessera-render writes PNG only; name the file .png";
  });
  app.add_option("--quality", a.quality_name, "reference | default | fast (default: the scene's)");
  app.add_option("--bricks", a.bricks, "split into N bricks and composite them like the farm")->check(CLI::Range(1, 4096));
  app.add_option("--frame", a.frame, "orbit frame K (and the time step the scene's playback shows in it)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--step", a.step, "time step N of a series (default: the step of --frame)")->check(CLI::NonNegativeNumber);
  app.add_option("--image", a.size, "image size WxH (default: the scene's)");
  app.add_option("--backend", a.backend, "volume backend: cpu (ray caster) | osmesa (GLSL on llvmpipe)")
      ->check(CLI::IsMember({"cpu", "osmesa"}))
      ->capture_default_str();
  app.add_option("--threads", a.threads, "ray-casting threads (0: all cores)")->check(CLI::NonNegativeNumber);
  app.add_flag("--stats", a.print_stats, "print time and sample counts (counted in one more, untimed render)");
  app.add_flag("--compare-reference", a.compare_ref, "also render at reference quality and print the error");
  app.add_flag("--no-skip", a.no_skip, "disable empty-space skipping (for measurements)");
  app.add_option("--repeat", a.repeat,
                 "render N times and report the fastest, and the mean after the first (for measurements)")->check(CLI::Range(1, 1000));
  app.add_option("--raw", a.raw, "also write premultiplied RGBA32F");
  app.add_option("--premultiplied", a.pam,
                 "also write premultiplied rgba8 as a PAM file (what farm comparisons use: exact values)");
  app.add_option("--background", a.background, "composite over r,g,b in [0,1] instead of writing alpha")
      ->delimiter(',')
      ->expected(3)
      ->check(CLI::Range(0.0, 1.0))
      ->option_text("R,G,B [none: straight alpha]");
  app.add_option("--window", a.window,
                 "the colour map through this window instead of the scene's `window`, as an interactive farm's "
                 "frame shows it (metrics.jsonl's `window`): centre and width in fractions of the volume's range")
      ->delimiter(',')
      ->expected(2)
      ->option_text("C,W [the scene's `window`; 0.5,1: the whole range]");
  app.add_option("--tiles", a.tiles, "mesh scenes: render as CxR tiles and assemble (bit-identical to 1x1)");
  app.add_option("--aa", a.aa, "mesh scenes: none | msaa | ssaa | fft (default: the scene's)");
  app.add_option("--aa-samples", a.aa_samples, "mesh scenes: MSAA samples (1,2,4) or SSAA factor")->check(CLI::Range(1, 8));
  app.add_flag("--aa-sweep", a.aa_sweep, "mesh scenes: CSV of every anti-aliasing method's time and error vs 16x SSAA");
}

int renderVolume(const Scene& scene, const Args& a, int w, int h, std::optional<std::array<double, 3>> bg) {
  renderer::RenderOptions opt;
  opt.quality = a.quality_name.empty() ? scene.quality
                                       : presetKeepingJitter(namedQuality(a.quality_name), scene.quality.jitter);
  if (a.no_skip) opt.quality.skip_empty = false;
  opt.threads = a.threads;
  const Camera cam = scene.orbit.at(scene.camera, a.frame);

  // A series is normalised with step 0's range (as the farm does), whatever step is shown.
  Scene fixed = scene;
  if (scene.series.steps > 1) fixVolumeRange(fixed);
  const int step = a.step >= 0 ? a.step : scene.time.stepAt(a.frame, scene.series.steps);
  auto vol = std::make_shared<const Volume>(loadVolume(fixed, VoxelBox{{0, 0, 0}, volumeDims(scene)}, step));
  Scene said_of = scene;  // --window replaces the scene's: nothing to say of that one
  if (!a.window.empty()) said_of.window.reset();
  for (const std::string& said : volumeWarnings(said_of, *vol)) std::fprintf(stderr, "tessera-render: warning: %s\n", said.c_str());
  // The scene's `window` over the values mapped (a file's `range`, or its data's), or the one asked for.
  const ColorWindow window = a.window.empty() ? colorWindow(scene, vol->mapped_range) : ColorWindow{a.window[0], a.window[1]};
  const TransferFunction tf = windowed(scene.tf, window);
  auto chosen = renderer::makeVolumeBackend(renderer::parseBackend(a.backend), vol, tf, scene.shading, scene.light,
                                            scene.blend, scene.crop);
  std::optional<MaxIntensity> mip;
  if (isProjection(scene.blend)) mip.emplace(tf, scene.blend == Blend::Minimum);
  const MaxIntensity* mp = mip ? &*mip : nullptr;
  // Split once, outside the timed renders, as the farm's master does once per run (no tree:
  // the whole volume, and no classification of every voxel for it).
  const BrickTree tree = a.bricks > 1 ? splitBricks(*vol, a.bricks, &tf) : BrickTree{};
  ImageF img;
  Rect drawn;
  renderer::RenderStats stats;
  double best_ms = 1e300, best_cpu_ms = 1e300;
  // The mean of the renders after the first: a steady stream's time per frame, which is what a
  // farm's frames a second compare with (its warm-up frames left out); the best of repeats is
  // the luckiest frame on a shared machine (in three runs of 11 on an Intel Xeon the mean was
  // 1.045-1.09x the best).
  double later_ms = 0;
  for (int r = 0; r < a.repeat; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    img.clear(drawn);  // each render in the memory of the one before (renderScene)
    img = renderScene(*chosen, *vol, tree, cam, w, h, opt, nullptr, mp, &drawn, std::move(img));
    best_cpu_ms = std::min(best_cpu_ms, 1000.0 * (double)(std::clock() - c0) / CLOCKS_PER_SEC);
    const double ms = msSince(t0);
    best_ms = std::min(best_ms, ms);
    if (r > 0) later_ms += ms;
  }
  // The counts from one more, untimed render: counting every skipped sample exactly costs
  // (4% of a default frame), and the times are those of a render as the farm runs it.
  if (a.print_stats) renderScene(*chosen, *vol, tree, cam, w, h, opt, &stats, mp);
  writePng(a.out, img, bg);
  std::printf("wrote %s (%dx%d, quality %s%s, %d brick%s, frame %d, step %d, backend %s)\n", a.out.c_str(), w, h,
              qualityName(opt.quality.name), opt.quality.jitter ? ", jittered" : "", a.bricks, a.bricks == 1 ? "" : "s",
              a.frame, step, a.backend.c_str());
  if (!a.raw.empty()) {
    writeRawF32(a.raw, img);
    std::printf("wrote %s\n", a.raw.c_str());
  }
  if (!a.pam.empty()) {
    writePam(a.pam, img);
    std::printf("wrote %s\n", a.pam.c_str());
  }
  if (a.print_stats) {
    std::printf("time_ms=%.1f cpu_ms=%.1f%s samples=%llu skipped=%llu terminated=%llu skip_empty=%d simd=%s gather=%s",
                best_ms, best_cpu_ms, a.repeat > 1 ? " (best of repeats)" : "", (unsigned long long)stats.samples,
                (unsigned long long)stats.samples_skipped, (unsigned long long)stats.samples_terminated,
                opt.quality.skip_empty ? 1 : 0, isaName(cpuIsa()), gathersName(cpuGathers()));
    if (a.repeat > 1) std::printf(" mean_ms=%.1f", later_ms / (a.repeat - 1));
    std::printf("\n");
  }
  if (a.compare_ref) {
    renderer::RenderOptions ropt = opt;
    ropt.quality = namedQuality(QualityName::Reference);
    const auto t0 = std::chrono::steady_clock::now();
    const ImageF ref = renderScene(*chosen, *vol, tree, cam, w, h, ropt, nullptr, mp);
    const double ref_ms = msSince(t0);
    const ImageError e = compare(img, ref);
    std::printf("vs reference: max_abs=%.6f rmse=%.6f psnr=%.2f dB (reference %.0f ms)\n", e.max_abs, e.rmse, e.psnr,
                ref_ms);
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"tessera-render: CPU ray casting of a Tessera scene in one process"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  Args a;
  addOptions(app, a);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "tessera-render: %s (see --help)\n", e.what());
    return 1;
  }

  Scene scene = a.scene_path.empty() ? defaultScene() : loadScene(a.scene_path);
  const std::optional<std::array<double, 3>> bg = backgroundColour(a.background);
  int w = scene.width, h = scene.height;
  if (!a.size.empty()) parseSize(a.size, w, h);
  // A camera fitted to the scene's image is fitted again to the size asked for (a tall one).
  if (scene.camera_fitted) scene.camera = fittedCamera(scene, (double)w / h);
  if (!scene.mesh) return renderVolume(scene, a, w, h, bg);
  if (!a.window.empty()) throw std::invalid_argument("--window: a mesh scene has no colour map");
  renderer::MeshToolOptions mo;
  mo.out = a.out;
  mo.width = w;
  mo.height = h;
  mo.frame = a.frame;
  parseSize(a.tiles, mo.tile_cols, mo.tile_rows);
  mo.repeat = a.repeat;
  mo.stats = a.print_stats;
  mo.compare_reference = a.compare_ref;
  mo.aa_sweep = a.aa_sweep;
  mo.aa = a.aa;
  mo.aa_samples = a.aa_samples;
  mo.background = bg;
  mo.pam = a.pam;
  return renderer::renderMeshScene(scene, mo);
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-render", [&] { return run(argc, argv); });
}
