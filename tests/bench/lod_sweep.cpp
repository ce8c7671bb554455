// tessera-lod-sweep: what an interactive frame should cost. While the camera moves, the farm
// renders reduced frames (fewer pixels, a longer step, earlier termination) that the window
// scales up; this sweep renders each mix at the reduced size, scales it up with the
// display's own resampler, and measures its error against the full frame the user sees
// once the mouse stops. Writes lod.csv, lod.png (gnuplot) and a markdown table whose
// Pareto-front rows (no other row both faster and more accurate) are marked.
// A benchmark, not a timed test.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "common/clock.h"
#include "common/resample.h"
#include "common/scene.h"
#include "common/volume_summary.h"
#include "renderer/tools/tool_main.h"
#include "renderer/volume/raycaster.h"

namespace {

using namespace tessera;
namespace fs = std::filesystem;

double processCpuMs() {  // all threads: steadier than wall time on a shared machine
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) / 1e6;
}

struct Row {
  double reduction = 1, step_l0 = 1, et = 1;
  int width = 0, height = 0;
  double ms = 0, cpu_ms = 0, upscale_ms = 0;
  ImageError err;
  bool pareto = false;
};

Row measure(const renderer::Raycaster& rc, const Volume& vol, const Scene& s, const Image8& full, double reduction, double step_l0,
            double et, int repeat, int threads) {
  Row row;
  row.reduction = reduction, row.step_l0 = step_l0, row.et = et;
  row.width = std::max(1, (int)std::lround(s.width / reduction));
  row.height = std::max(1, (int)std::lround(s.height / reduction));
  renderer::RenderOptions opt;
  opt.threads = threads;
  opt.quality = s.quality;
  opt.quality.name = QualityName::Custom;
  opt.quality.step = step_l0 * kL0;
  opt.quality.early_termination = et;
  row.ms = row.cpu_ms = 1e300;
  Image8 small;
  for (int r = 0; r < repeat; ++r) {
    const auto t0 = Clock::now();
    const double c0 = processCpuMs();
    small = toRGBA8(rc.render(s.camera, row.width, row.height, renderer::wholeVolume(vol), opt));
    row.cpu_ms = std::min(row.cpu_ms, processCpuMs() - c0);
    row.ms = std::min(row.ms, msSince(t0));
  }
  const auto t1 = Clock::now();
  const Image8 shown = resizeBilinear(small, s.width, s.height);
  row.upscale_ms = msSince(t1);
  row.err = compare(shown, full);
  return row;
}

void markPareto(std::vector<Row>& rows) {
  for (Row& r : rows) {
    r.pareto = true;
    for (const Row& o : rows)
      if (&o != &r && o.cpu_ms <= r.cpu_ms && o.err.psnr >= r.err.psnr && (o.cpu_ms < r.cpu_ms || o.err.psnr > r.err.psnr))
        r.pareto = false;
  }
}

// The Pareto rows by cost (finite PSNR: the full frame itself is not a point), for the plot's line.
void writePareto(const std::string& path, std::vector<Row> rows) {
  std::erase_if(rows, [](const Row& r) { return !r.pareto || !std::isfinite(r.err.psnr); });
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.cpu_ms < b.cpu_ms; });
  std::ofstream o(path);
  for (const Row& r : rows)
    o << r.reduction << ',' << r.step_l0 << ',' << r.et << ',' << r.width << ',' << r.height << ',' << r.ms << ','
      << r.cpu_ms << ',' << r.upscale_ms << ',' << r.err.psnr << '\n';
}

void writeCsv(const std::string& path, const std::vector<Row>& rows) {
  std::ofstream o(path);
  o << "reduction,step_l0,et,width,height,ms,cpu_ms,upscale_ms,psnr_db,max_abs,pareto\n";
  for (const Row& r : rows)
    o << r.reduction << ',' << r.step_l0 << ',' << r.et << ',' << r.width << ',' << r.height << ',' << r.ms << ','
      << r.cpu_ms << ',' << r.upscale_ms << ',' << r.err.psnr << ',' << r.err.max_abs << ',' << (r.pareto ? 1 : 0)
      << '\n';
}

bool plot(const std::string& dir, const std::string& title) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    std::fprintf(stderr, "tessera-lod-sweep: gnuplot not found (apt-get install gnuplot-nox); no plot\n");
    return false;
  }
  std::ofstream gp(dir + "/lod.gp");
  gp << "set terminal pngcairo size 900,600\nset output '" << dir << "/lod.png'\n"
     << "set datafile separator ','\nset key bottom right\nset grid\n"
     << "set title '" << title << "'\nset xlabel 'CPU ms per frame (render)'\nset ylabel 'PSNR vs the full frame (dB)'\n"
     << "set logscale x\n"
     << "plot for [r in '1 1.5 2 3 4'] '" << dir << "/lod.csv' skip 1 using ($1==r+0 ? $7 : 1/0):9 with points pt 7 "
     << "title 'reduction '.r, \\\n  '" << dir << "/lod-pareto.csv' using 7:9 with lines lw 2 lc 'black' title 'Pareto front'\n";
  gp.close();
  if (std::system(("gnuplot '" + dir + "/lod.gp' 2>'" + dir + "/gnuplot.log'").c_str()) != 0) {
    std::fprintf(stderr, "tessera-lod-sweep: gnuplot failed, see %s/gnuplot.log\n", dir.c_str());
    return false;
  }
  return true;
}

int run(int argc, char** argv) {
  CLI::App app{"tessera-lod-sweep: cost against error of reduced interactive frames (size, step, termination)"};
  std::string scene_path, out = "bench-out/lod";
  int repeat = 3, threads = 0;
  app.add_option("scene", scene_path, "scene file (default: the built-in hollow shell)");
  app.add_option("--out", out, "output folder (lod.csv, lod.png)")->capture_default_str();
  app.add_option("--repeat", repeat, "renders per mix; the best counts")->capture_default_str()->check(CLI::Range(1, 100));
  app.add_option("--threads", threads, "ray-casting threads (0: all cores)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  Scene s = scene_path.empty() ? defaultScene() : loadScene(scene_path);
  if (s.mesh) throw std::invalid_argument("tessera-lod-sweep: a volume scene is needed, not a geometry scene");
  if (s.blend != Blend::Composite) throw std::invalid_argument(std::string("tessera-lod-sweep: composite scenes only, not blend: ") + blendName(s.blend));
  if (!s.crop.whole()) throw std::invalid_argument("tessera-lod-sweep: whole volumes only, leave out `crop`");
  fixVolumeRange(s);
  s.tf = windowed(s.tf, colorWindow(s));  // the scene's `window`, as the farm shows it
  fs::create_directories(out);
  auto vol = std::make_shared<const Volume>(loadVolume(s));
  const renderer::Raycaster rc(vol, s.tf, s.shading, s.light);
  renderer::RenderOptions full_opt;
  full_opt.threads = threads;
  full_opt.quality = s.quality;
  const Image8 full = toRGBA8(rc.render(s.camera, s.width, s.height, renderer::wholeVolume(*vol), full_opt));
  std::vector<Row> rows;
  for (double reduction : {1.0, 1.5, 2.0, 3.0, 4.0})
    for (double step : {1.0, 2.0, 4.0})
      for (double et : {s.quality.early_termination, 0.95}) {
        rows.push_back(measure(rc, *vol, s, full, reduction, step, et, repeat, threads));
        const Row& r = rows.back();
        std::fprintf(stderr, "reduction %-3g step %g ET %-6.4g %4dx%-4d %7.1f ms (cpu %7.1f) upscale %5.1f ms PSNR %6.2f dB\n",
                     reduction, step, et, r.width, r.height, r.ms, r.cpu_ms, r.upscale_ms, r.err.psnr);
      }
  markPareto(rows);
  writeCsv(out + "/lod.csv", rows);
  writePareto(out + "/lod-pareto.csv", rows);
  plot(out, fmt::format("{} {}x{}: interactive frames against the full frame", scene_path.empty() ? "default scene" : scene_path, s.width, s.height));
  std::printf("| reduction | step (voxels) | ET | size | ms | CPU ms | upscale ms | PSNR dB | Pareto |\n|---:|---:|---:|---|---:|---:|---:|---:|:-:|\n");
  for (const Row& r : rows)
    std::printf("| %g | %g | %.4g | %dx%d | %.1f | %.1f | %.1f | %.1f | %s |\n", r.reduction, r.step_l0, r.et, r.width,
                r.height, r.ms, r.cpu_ms, r.upscale_ms, r.err.psnr, r.pareto ? "yes" : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-lod-sweep", [&] { return run(argc, argv); });
}
