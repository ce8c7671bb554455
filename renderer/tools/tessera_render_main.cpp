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
#include "common/scene.h"
#include "renderer/volume/backend.h"
#include "renderer/tools/mesh_render_tool.h"

namespace {

using namespace tessera;

std::array<double, 3> parseBackground(const std::string& s) {
  std::array<double, 3> c{};
  std::stringstream in(s);
  std::string part;
  int i = 0;
  while (std::getline(in, part, ',')) {
    if (i >= 3) throw std::invalid_argument("--background: expected r,g,b, got '" + s + "'");
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != part.size() || !(v >= 0 && v <= 1))
      throw std::invalid_argument("--background: components must be numbers in [0,1], got '" + s + "'");
    c[i++] = v;
  }
  if (i != 3) throw std::invalid_argument("--background: expected r,g,b, got '" + s + "'");
  return c;
}

void parseSize(const std::string& s, int& w, int& h) {
  char x = 0;
  int a = 0, b = 0;
  char rest = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &a, &x, &b, &rest) != 3 || (x != 'x' && x != 'X') || a <= 0 || b <= 0 ||
      a > 16384 || b > 16384)
    throw std::invalid_argument("--size: expected WxH with 1..16384 each, got '" + s + "'");
  w = a;
  h = b;
}

// Renders the scene whole (bricks <= 1) or as bricks composited in visibility order.
ImageF renderScene(const renderer::VolumeBackend& rc, const Volume& vol, const TransferFunction& tf, const Camera& cam,
                   int w, int h, int bricks, const renderer::RenderOptions& opt, renderer::RenderStats& stats) {
  if (bricks <= 1) return rc.render(cam, w, h, renderer::wholeVolume(vol), opt, &stats);
  const BrickTree tree = splitBricks(vol, bricks, &tf);
  ImageF out(w, h);
  for (int leaf : tree.visibilityOrder(vol, cam)) {
    renderer::RenderStats s;
    Rect active;
    const ImageF part = rc.render(cam, w, h, tree.bricks[leaf], opt, &s, &active);
    if (!active.empty()) compositeOver(out, part, active);
    stats += s;
  }
  return out;
}

int run(int argc, char** argv) {
  CLI::App app{"tessera-render: CPU ray casting of a Tessera scene in one process"};
  std::string scene_path, out = "out.png", quality_name, size, raw, pam, background, backend = "cpu";
  int bricks = 1, frame = 0, threads = 0, repeat = 1;
  bool print_stats = false, compare_ref = false, no_skip = false;
  app.add_option("scene", scene_path, "scene file (default: the built-in hollow shell)");
  // The extension says the format: only PNG is written, so any other is refused by name
  // rather than writing PNG bytes into a file called .jpg.
  app.add_option("-o,--output", out, "output PNG (.png)")->capture_default_str()->check([](const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    return ext == ".png" || ext == ".PNG" ? std::string()
                                          : "'" + path + "': tessera-render writes PNG only; name the file .png";
  });
  app.add_option("--quality", quality_name, "reference | default | fast (default: the scene's)");
  app.add_option("--bricks", bricks, "split into N bricks and composite them like the farm")->check(CLI::Range(1, 4096));
  app.add_option("--frame", frame, "orbit frame K")->check(CLI::NonNegativeNumber);
  app.add_option("--size", size, "image size WxH (default: the scene's)");
  app.add_option("--backend", backend, "volume backend: cpu (ray caster) | osmesa (GLSL on llvmpipe)")
      ->check(CLI::IsMember({"cpu", "osmesa"}))
      ->capture_default_str();
  app.add_option("--threads", threads, "ray-casting threads (0: all cores)")->check(CLI::NonNegativeNumber);
  app.add_flag("--stats", print_stats, "print time and sample counts");
  app.add_flag("--compare-reference", compare_ref, "also render at reference quality and print the error");
  app.add_flag("--no-skip", no_skip, "disable empty-space skipping (for measurements)");
  app.add_option("--repeat", repeat, "render N times and report the fastest (for measurements)")->check(CLI::Range(1, 1000));
  app.add_option("--raw", raw, "also write premultiplied RGBA32F");
  app.add_option("--premultiplied", pam,
                 "also write premultiplied rgba8 as a PAM file (what farm comparisons use: exact values)");
  app.add_option("--background", background, "composite over r,g,b in [0,1] instead of writing alpha");
  // Mesh scenes (OSMesa): tiles, anti-aliasing overrides and the anti-aliasing sweep.
  std::string tiles = "1x1", aa;
  int aa_samples = 0;
  bool aa_sweep = false;
  app.add_option("--tiles", tiles, "mesh scenes: render as CxR tiles and assemble (bit-identical to 1x1)");
  app.add_option("--aa", aa, "mesh scenes: none | msaa | ssaa | fft (default: the scene's)");
  app.add_option("--aa-samples", aa_samples, "mesh scenes: MSAA samples (1,2,4) or SSAA factor")->check(CLI::Range(1, 8));
  app.add_flag("--aa-sweep", aa_sweep, "mesh scenes: CSV of every anti-aliasing method's time and error vs 16x SSAA");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "tessera-render: %s (see --help)\n", e.what());
    return 1;
  }

  const Scene scene = scene_path.empty() ? defaultScene() : loadScene(scene_path);
  std::optional<std::array<double, 3>> bg;
  if (!background.empty()) bg = parseBackground(background);
  int w = scene.width, h = scene.height;
  if (!size.empty()) parseSize(size, w, h);
  if (scene.mesh) {
    renderer::MeshToolOptions mo;
    mo.out = out;
    mo.width = w;
    mo.height = h;
    mo.frame = frame;
    parseSize(tiles, mo.tile_cols, mo.tile_rows);
    mo.repeat = repeat;
    mo.stats = print_stats;
    mo.compare_reference = compare_ref;
    mo.aa_sweep = aa_sweep;
    mo.aa = aa;
    mo.aa_samples = aa_samples;
    mo.background = bg;
    mo.pam = pam;
    return renderer::renderMeshScene(scene, mo);
  }
  renderer::RenderOptions opt;
  opt.quality = quality_name.empty() ? scene.quality : namedQuality(quality_name);
  if (no_skip) opt.quality.skip_empty = false;
  opt.threads = threads;
  const Camera cam = scene.orbit.at(scene.camera, frame);

  auto vol = std::make_shared<const Volume>(loadVolume(scene));
  auto chosen = renderer::makeVolumeBackend(renderer::parseBackend(backend), vol, scene.tf);
  ImageF img;
  renderer::RenderStats stats;
  double best_ms = 1e300, best_cpu_ms = 1e300;
  for (int r = 0; r < repeat; ++r) {
    stats = {};
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    img = renderScene(*chosen, *vol, scene.tf, cam, w, h, bricks, opt, stats);
    best_cpu_ms = std::min(best_cpu_ms, 1000.0 * (double)(std::clock() - c0) / CLOCKS_PER_SEC);
    best_ms = std::min(best_ms, msSince(t0));
  }
  writePng(out, img, bg);
  std::printf("wrote %s (%dx%d, quality %s, %d brick%s, frame %d, backend %s)\n", out.c_str(), w, h,
              qualityName(opt.quality.name), bricks, bricks == 1 ? "" : "s", frame, backend.c_str());
  if (!raw.empty()) {
    writeRawF32(raw, img);
    std::printf("wrote %s\n", raw.c_str());
  }
  if (!pam.empty()) {
    writePam(pam, img);
    std::printf("wrote %s\n", pam.c_str());
  }
  if (print_stats)
    std::printf("time_ms=%.1f cpu_ms=%.1f%s samples=%llu skipped=%llu terminated=%llu skip_empty=%d simd=%s\n",
                best_ms, best_cpu_ms, repeat > 1 ? " (best of repeats)" : "", (unsigned long long)stats.samples,
                (unsigned long long)stats.samples_skipped, (unsigned long long)stats.samples_terminated,
                opt.quality.skip_empty ? 1 : 0, isaName(cpuIsa()));
  if (compare_ref) {
    renderer::RenderOptions ropt = opt;
    ropt.quality = namedQuality(QualityName::Reference);
    renderer::RenderStats rs;
    const ImageF ref = renderScene(*chosen, *vol, scene.tf, cam, w, h, bricks, ropt, rs);
    const ImageError e = compare(img, ref);
    std::printf("vs reference: max_abs=%.6f rmse=%.6f psnr=%.2f dB (reference %.0f ms)\n", e.max_abs, e.rmse, e.psnr,
                rs.ms);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-render", [&] { return run(argc, argv); });
}
