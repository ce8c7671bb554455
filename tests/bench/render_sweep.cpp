// tessera-sweep: speed against error of the CPU ray caster over step size, early-termination
// threshold and empty-space skipping, on the built-in generator scenes. Every configuration
// is judged against the reference render (double precision, step L0/16), which is cached as
// raw float in the output folder. Writes sweep.csv, PNG plots (gnuplot) and a markdown table.
// A benchmark, not a timed test: exits 2 only when a counting invariant breaks.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "renderer/tools/tool_main.h"
#include "common/clock.h"
#include "common/io/image_io.h"
#include "common/scene.h"
#include "tests/bench/render_sweep_report.h"
#include "renderer/volume/raycaster.h"

namespace {

using namespace tessera;
namespace fs = std::filesystem;

// CPU time of the whole process (all threads): unlike wall time it does not grow while other
// programs hold the shared cores, so it is the steadier speed figure on a busy machine.
double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) / 1e6;
}

// The transfer function and camera come from a shipped scene file with this generator if
// there is one, else from the built-in default scene; the volume size is always ours.
Scene sceneFor(const std::string& generator, int size, const std::string& scenes_dir) {
  if (!scenes_dir.empty() && fs::is_directory(scenes_dir)) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(scenes_dir))
      if (e.path().extension() == ".yaml" || e.path().extension() == ".yml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      Scene s;
      try {
        s = loadScene(f.string());
      } catch (const std::exception& e) {
        static std::vector<fs::path> reported;  // say it once, not once per scene
        if (std::find(reported.begin(), reported.end(), f) == reported.end())
          std::fprintf(stderr, "tessera-sweep: not a volume scene we can use, skipped: %s\n", e.what());
        reported.push_back(f);
        continue;
      }
      auto* g = std::get_if<GeneratorSpec>(&s.volume);
      // Geometry scenes (an isosurface of a generated volume) carry no transfer function.
      // A maximum intensity projection (mip.yaml), a cut volume (cut-head.yaml) or a colour
      // window is not the scene's whole composite frame the sweep times.
      if (g && g->name == generator && !s.mesh && !s.tf.points().empty() && s.blend == Blend::Composite &&
          s.crop.whole() && !s.window) {
        g->size = size;
        return s;
      }
    }
  }
  Scene s = defaultScene();
  s.volume = GeneratorSpec{generator, size, 1, {1, 1, 1}};
  return s;
}

// Cache key: the scene, the image size and the volume's values name the file; a change in
// the renderer's reference path is caught by the fingerprint check in the caller.
std::string referenceKey(const std::string& name, const Scene& s, const Volume& v, int w, int h) {
  std::ostringstream o;
  const auto& g = std::get<GeneratorSpec>(s.volume);
  o << g.name << g.size << g.seed << g.spacing[0] << g.spacing[1] << g.spacing[2];
  for (const auto& p : s.tf.points()) o << p.s << p.r << p.g << p.b << p.a;
  const Camera& c = s.camera;
  o << c.eye.x << c.eye.y << c.eye.z << c.target.x << c.target.y << c.target.z << c.up.x << c.up.y << c.up.z << c.fov
    << c.orthographic << c.height;
  uint64_t hash = 1469598103934665603ull;  // FNV-1a
  for (char ch : o.str()) hash = (hash ^ (unsigned char)ch) * 1099511628211ull;
  for (float f : v.values) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    hash = (hash ^ u) * 1099511628211ull;
  }
  char buf[256];
  std::snprintf(buf, sizeof buf, "ref-%s-%d-%dx%d-%016llx.f32", name.c_str(), g.size, w, h, (unsigned long long)hash);
  return buf;
}

// Reads what writeRawF32 wrote; false if missing or not this size.
bool readRawF32(const std::string& path, int w, int h, ImageF& img) {
  std::ifstream in(path, std::ios::binary);
  char magic[8];
  uint32_t dims[2];
  if (!in.read(magic, 8) || std::memcmp(magic, "TSRAWF32", 8) != 0) return false;
  if (!in.read(reinterpret_cast<char*>(dims), 8) || dims[0] != uint32_t(w) || dims[1] != uint32_t(h)) return false;
  img = ImageF(w, h);  // little-endian host, like every machine the farm runs on
  return bool(in.read(reinterpret_cast<char*>(img.px.data()), std::streamsize(img.px.size() * sizeof(float))));
}

void parseImage(const std::string& s, int& w, int& h) {
  char x = 0, rest = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &rest) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 16384 || h > 16384)
    throw std::invalid_argument("--image: expected WxH, got '" + s + "'");
}

std::string clockText(double ms) {
  const long s = long(ms / 1000 + 0.5);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

struct Config {
  double step_l0, et;
  bool skip;
};

struct Args {
  int size = 256, repeat = 3, threads = 0, w = 1024, h = 1024;
  std::string out_dir = "bench-out", scenes_dir = TESSERA_SOURCE_DIR "/scenes", replot;
  std::vector<std::string> names{"hollow-shell", "marschner-lobb", "noise-cloud"};
  bool no_plot = false;
};

// Fills `a` from the command line; returns -1 to go on, else the exit code (help, bad option).
int parseArgs(int argc, char** argv, Args& a) {
  CLI::App app{"tessera-sweep: ray-caster speed vs error over step, early termination and skipping"};
  std::string image = "1024x1024";
  app.add_option("--volume-size", a.size, "generated volume edge in voxels")->capture_default_str()->check(CLI::Range(2, 2048));
  app.add_option("--image", image, "image size WxH")->capture_default_str();
  app.add_option("--repeat", a.repeat, "renders per configuration; the best wall time counts")
      ->capture_default_str()->check(CLI::Range(1, 100));
  app.add_option("--threads", a.threads, "ray-casting threads (0: all cores)")->check(CLI::NonNegativeNumber);
  app.add_option("--out", a.out_dir, "output folder (CSV, plots, cached references)")->capture_default_str();
  app.add_option("--scenes", a.names, "generator scenes to sweep")->capture_default_str();
  app.add_option("--scenes-dir", a.scenes_dir, "shipped scene files (transfer function, camera)")->capture_default_str();
  app.add_flag("--no-plot", a.no_plot, "do not run gnuplot");
  app.add_option("--replot", a.replot, "render nothing: re-plot and re-print this sweep.csv into --out");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "tessera-sweep: %s (see --help)\n", e.what());
    return 1;
  }
  parseImage(image, a.w, a.h);
  return -1;
}

// --replot: the plots and tables of an existing sweep.csv, rendering nothing.
int replot(const Args& a) {
  const auto rows = bench::readCsv(a.replot);
  std::vector<std::string> seen;
  for (const auto& r : rows)
    if (std::find(seen.begin(), seen.end(), r.scene) == seen.end()) seen.push_back(r.scene);
  if (!a.no_plot) bench::plot(a.out_dir, rows, seen);
  std::printf("%s\n%s", bench::markdownTable(rows).c_str(), bench::defaultSummary(rows).c_str());
  return 0;
}

// The reference render of a scene, from the cache in --out when it is still valid.
ImageF referenceImage(const Args& a, const std::string& name, const Scene& scene, const Volume& vol,
                      const renderer::Raycaster& rc) {
  const std::string ref_path = a.out_dir + "/" + referenceKey(name, scene, vol, a.w, a.h);
  renderer::RenderOptions ropt;
  ropt.quality = namedQuality("reference");
  ropt.threads = a.threads;
  // A 32x32 reference rendered now must match the one stored with the cache bit for bit,
  // or the renderer's reference path changed since and the cache is stale.
  const ImageF fingerprint = rc.render(scene.camera, 32, 32, renderer::wholeVolume(vol), ropt);
  ImageF ref, cached_fp;
  if (readRawF32(ref_path + ".fp", 32, 32, cached_fp) && cached_fp == fingerprint &&
      readRawF32(ref_path, a.w, a.h, ref)) {
    std::fprintf(stderr, "[%s] reference from cache %s\n", name.c_str(), ref_path.c_str());
    return ref;
  }
  std::fprintf(stderr, "[%s] rendering the reference (double, step L0/16) at %dx%d...\n", name.c_str(), a.w, a.h);
  const auto t0 = Clock::now();
  ref = rc.render(scene.camera, a.w, a.h, renderer::wholeVolume(vol), ropt);
  writeRawF32(ref_path, ref);
  writeRawF32(ref_path + ".fp", fingerprint);
  std::fprintf(stderr, "[%s] reference took %s, cached as %s\n", name.c_str(), clockText(msSince(t0)).c_str(),
               ref_path.c_str());
  return ref;
}

// One configuration rendered --repeat times: the last image and stats, every repeat's times.
struct Timed {
  ImageF img;
  renderer::RenderStats st;
  std::vector<double> times, cpu_times;  // wall times sorted
  double total_ms = 0;
};

Timed timeConfig(const Args& a, const renderer::Raycaster& rc, const Camera& cam, const Volume& vol,
                 const Config& c) {
  renderer::RenderOptions opt;
  opt.threads = a.threads;
  opt.quality.name = QualityName::Custom;
  opt.quality.step = c.step_l0 * kL0;
  opt.quality.early_termination = c.et;
  opt.quality.skip_empty = c.skip;
  Timed t;
  const auto t_cfg = Clock::now();
  for (int r = 0; r < a.repeat; ++r) {
    t.st = {};
    const auto t0 = Clock::now();
    const double c0 = processCpuMs();
    t.img = rc.render(cam, a.w, a.h, renderer::wholeVolume(vol), opt, &t.st);
    t.cpu_times.push_back(processCpuMs() - c0);
    t.times.push_back(msSince(t0));
  }
  t.total_ms = msSince(t_cfg);
  std::sort(t.times.begin(), t.times.end());
  return t;
}

// Runs every configuration on every scene, collecting rows and counting broken invariants.
class Sweep {
 public:
  explicit Sweep(const Args& a) : a_(a) {
    for (double step : {0.5, 1.0, 2.0, 4.0})
      for (double et : {0.95, 0.99, default_et_, 2.0})
        for (bool skip : {false, true}) configs_.push_back({step, et, skip});  // off first: on is compared to it
    total_ = configs_.size() * a.names.size();
  }
  void runScene(const std::string& name);
  const std::vector<bench::SweepRow>& rows() const { return rows_; }
  int violations() const { return violations_; }

 private:
  bench::SweepRow makeRow(const std::string& name, const Config& c, const Timed& t, const ImageF& ref) const;
  void check(const std::string& id, const Config& c, const bench::SweepRow& row);
  void violation(const std::string& what) {
    std::fprintf(stderr, "tessera-sweep: INVARIANT BROKEN: %s\n", what.c_str());
    ++violations_;
  }

  const Args& a_;
  const double default_et_ = namedQuality("default").early_termination;
  std::vector<Config> configs_;
  size_t total_ = 0, done_ = 0;
  double sweep_ms_ = 0;
  int violations_ = 0;
  std::vector<bench::SweepRow> rows_;
  uint64_t grid_total_ = 0;  // samples on the ray grid of the current step, however spent
};

void Sweep::runScene(const std::string& name) {
  const Scene scene = sceneFor(name, a_.size, a_.scenes_dir);
  auto t_gen = Clock::now();
  auto vol = std::make_shared<const Volume>(loadVolume(scene));
  const renderer::Raycaster rc(vol, scene.tf);
  std::fprintf(stderr, "[%s] %d^3 volume (tf/camera from %s) ready in %.0f ms\n", name.c_str(), a_.size,
               scene.path.empty() ? "the default scene" : scene.path.c_str(), msSince(t_gen));
  const ImageF ref = referenceImage(a_, name, scene, *vol, rc);
  ImageF no_skip_img;
  grid_total_ = 0;
  for (const Config& c : configs_) {
    Timed t = timeConfig(a_, rc, scene.camera, *vol, c);
    sweep_ms_ += t.total_ms;
    bench::SweepRow r = makeRow(name, c, t, ref);
    const std::string id = name + " step " + std::to_string(c.step_l0) + " ET " + bench::etLabel(c.et) + " skip " +
                           (c.skip ? "on" : "off");
    check(id, c, r);
    if (c.skip) r.skip_vs_noskip = compare(t.img, no_skip_img).max_abs;
    else no_skip_img = std::move(t.img);
    rows_.push_back(r);

    ++done_;
    const double eta = sweep_ms_ / double(done_) * double(total_ - done_);
    std::fprintf(stderr, "[%zu/%zu] %-14s step %-3g ET %-9s skip %-3s %8.1f ms %7.1f Msamples PSNR %6.2f dB  ETA %s\n",
                 done_, total_, name.c_str(), c.step_l0, bench::etLabel(c.et).c_str(), c.skip ? "on" : "off",
                 r.ms_best, double(r.samples) / 1e6, r.psnr, clockText(eta).c_str());
  }
}

bench::SweepRow Sweep::makeRow(const std::string& name, const Config& c, const Timed& t, const ImageF& ref) const {
  bench::SweepRow row;
  row.scene = name;
  row.size = a_.size;
  row.width = a_.w;
  row.height = a_.h;
  row.step_l0 = c.step_l0;
  row.et = c.et;
  row.skip = c.skip;
  row.is_default = c.step_l0 == 1.0 && c.et == default_et_ && c.skip;
  row.ms_best = t.times.front();
  row.ms_median = t.times[t.times.size() / 2];
  row.cpu_ms_best = *std::min_element(t.cpu_times.begin(), t.cpu_times.end());
  row.samples = t.st.samples;
  row.skipped = t.st.samples_skipped;
  row.terminated = t.st.samples_terminated;
  const ImageError e = compare(t.img, ref);
  row.max_abs = e.max_abs;
  row.rmse = e.rmse;
  row.psnr = e.psnr;
  return row;
}

// The counting invariants of one row; the grid note compares against the first config of each step.
void Sweep::check(const std::string& id, const Config& c, const bench::SweepRow& row) {
  if (std::isnan(row.psnr) || std::isnan(row.max_abs)) violation(id + ": non-finite image");
  if (!c.skip && row.skipped != 0) violation(id + ": samples skipped with skipping off");
  if (c.et > 1 && row.terminated != 0) violation(id + ": samples terminated with early termination off");
  if (row.samples == 0) violation(id + ": no samples taken");
  const uint64_t grid = row.samples + row.skipped + row.terminated;
  if (c.et == 0.95 && !c.skip) grid_total_ = grid;  // first config of each step
  else if (grid != grid_total_)
    std::fprintf(stderr, "tessera-sweep: note: %s: %llu grid samples, %llu with skipping off at ET 0.95\n",
                 id.c_str(), (unsigned long long)grid, (unsigned long long)grid_total_);
}

int run(int argc, char** argv) {
  Args a;
  if (const int rc = parseArgs(argc, argv, a); rc >= 0) return rc;
  fs::create_directories(a.out_dir);
  if (!a.replot.empty()) return replot(a);

  Sweep sweep(a);
  for (const std::string& name : a.names) sweep.runScene(name);
  const auto& rows = sweep.rows();
  bench::writeCsv(a.out_dir + "/sweep.csv", rows);
  std::fprintf(stderr, "wrote %s/sweep.csv\n", a.out_dir.c_str());
  if (!a.no_plot && bench::plot(a.out_dir, rows, a.names))
    std::fprintf(stderr, "wrote %s/render-sweep.png and %s/render-sweep-speedup.png\n", a.out_dir.c_str(),
                 a.out_dir.c_str());
  std::printf("%s\n%s", bench::markdownTable(rows).c_str(), bench::defaultSummary(rows).c_str());
  if (sweep.violations()) {
    std::fprintf(stderr, "tessera-sweep: %d invariant(s) broken\n", sweep.violations());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tessera::toolMain("tessera-sweep", [&] { return run(argc, argv); });
}
