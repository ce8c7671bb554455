// Anti-aliasing sweep (see aa_sweep.h).
#include "tests/bench/aa_sweep.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "common/clock.h"
#include "renderer/tools/fft_filter.h"

namespace tessera::bench {

using renderer::GlRenderOptions;

namespace {

// One whole-image render (the post filter needs the whole image, see fft_filter.h).
Image8 renderOnce(renderer::GlRenderer& r, const renderer::SceneGeometry& g, const Camera& cam, int w, int h,
                  const GlRenderOptions& base, const AaRow& m, double* filter_ms) {
  GlRenderOptions o = base;
  o.samples = m.method == AaMethod::Msaa ? m.samples : 1;
  o.supersample = m.method == AaMethod::Ssaa ? m.samples : 1;
  Image8 img = r.render(cam, w, h, Rect{0, 0, w, h}, g.chunks, o);
  if (m.method == AaMethod::Fft) {
    const auto t0 = Clock::now();
    renderer::lowPassFilter(img, m.sigma);
    *filter_ms = msSince(t0);
  }
  return img;
}

AaRow row(AaMethod method, int samples = 1, double sigma = 0) {
  AaRow m;
  m.method = method;
  m.samples = samples;
  m.sigma = sigma;
  return m;
}

}  // namespace

std::string AaRow::label() const {
  if (method == AaMethod::Msaa) return fmt::format("msaa {}", samples);
  if (method == AaMethod::Ssaa) return fmt::format("ssaa {}x{}", samples, samples);
  if (method == AaMethod::Fft) return fmt::format("fft s={:g}", sigma);
  return aaMethodName(method);
}

AaSweepResult aaSweep(renderer::GlRenderer& r, const renderer::SceneGeometry& g, const Camera& cam, int width,
                      int height, const GlRenderOptions& base, int repeat) {
  AaSweepResult res;
  res.width = width;
  res.height = height;
  res.triangles = g.mesh.triangleCount();
  double unused = 0;
  const AaRow ref_method = row(AaMethod::Ssaa, 4);
  // Warm-up: llvmpipe compiles shaders per state on first use; keep that out of the rows.
  (void)renderOnce(r, g, cam, width, height, base, row(AaMethod::None), &unused);
  (void)renderOnce(r, g, cam, width, height, base, ref_method, &unused);
  auto t0 = Clock::now();
  const Image8 ref = renderOnce(r, g, cam, width, height, base, ref_method, &unused);
  res.reference_ms = msSince(t0);

  using enum AaMethod;
  const std::vector<AaRow> methods = {row(None),        row(Msaa, 2),     row(Msaa, 4),     row(Ssaa, 2),
                                      row(Ssaa, 3),     row(Fft, 1, 0.4), row(Fft, 1, 0.6), row(Fft, 1, 0.8),
                                      row(Fft, 1, 1.0), row(Fft, 1, 1.5)};
  Image8 previous;
  for (AaRow m : methods) {
    Image8 img;
    m.ms = m.filter_ms = 1e300;
    // i == -1 warms up: llvmpipe JIT-compiles each new state (sample count, target size).
    for (int i = -1; i < std::max(1, repeat); ++i) {
      double filter_ms = 0;
      t0 = Clock::now();
      img = renderOnce(r, g, cam, width, height, base, m, &filter_ms);
      if (i < 0) continue;
      m.ms = std::min(m.ms, msSince(t0));
      m.filter_ms = std::min(m.filter_ms, filter_ms);
    }
    if (m.method != AaMethod::Fft) m.filter_ms = 0;
    m.err = compare(img, ref);
    m.same_as_previous = !res.rows.empty() && img.px == previous.px;
    previous = std::move(img);
    res.rows.push_back(m);
  }
  return res;
}

void writeAaCsv(const std::string& path, const AaSweepResult& res) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "method,samples,sigma,label,ms,filter_ms,rmse,psnr_db,max_abs\n";
  for (const AaRow& m : res.rows)
    f << fmt::format("{},{},{},{},{:.2f},{:.2f},{:.6f},{:.3f},{:.5f}\n", aaMethodName(m.method), m.samples, m.sigma, m.label(), m.ms,
                     m.filter_ms, m.err.rmse, m.err.psnr, m.err.max_abs);
}

bool plotAa(const std::string& csv_path, const std::string& png_path, const std::string& title) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    std::fprintf(stderr, "gnuplot not found (apt-get install gnuplot-nox); no %s\n", png_path.c_str());
    return false;
  }
  const std::string gp = png_path + ".gp";
  {
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1200,520 font 'Sans,10'\n"
      << "set output '" << png_path << "'\n"
      << "set datafile separator ','\n"
      << "set key off\nset grid\nset multiplot layout 1,2 title '" << title << "'\n"
      << "set xlabel 'run time per frame (ms, best of repeats)'\n"
      << "set ylabel 'RMSE vs 16x supersampled (RGBA in [0,1])'\nset logscale y\n"
      << "plot '" << csv_path << "' every ::1 using 5:7 with points pt 7 ps 1.3 lc rgb '#1f77b4', "
      << "'' every ::1 using 5:7:4 with labels offset 0,0.9 font 'Sans,9'\n"
      << "unset logscale y\nset ylabel 'PSNR vs 16x supersampled (dB)'\n"
      << "plot '" << csv_path << "' every ::1 using 5:8 with points pt 7 ps 1.3 lc rgb '#d62728', "
      << "'' every ::1 using 5:8:4 with labels offset 0,0.9 font 'Sans,9'\n"
      << "unset multiplot\n";
  }
  const std::string cmd = "gnuplot '" + gp + "' 2>'" + gp + ".log'";
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "gnuplot failed, see %s.log\n", gp.c_str());
    return false;
  }
  return true;
}

std::string aaMarkdown(const AaSweepResult& res) {
  std::string s = fmt::format(
      "Anti-aliasing, {}x{}, {} triangles; reference: 16x supersampled (4x4), {:.0f} ms.\n\n"
      "| method | ms (best) | of which post filter ms | RMSE | PSNR dB | max abs | note |\n"
      "|---|---|---|---|---|---|---|\n",
      res.width, res.height, res.triangles, res.reference_ms);
  for (const AaRow& m : res.rows)
    s += fmt::format("| {} | {:.1f} | {} | {:.5f} | {:.2f} | {:.4f} | {} |\n", m.label(), m.ms,
                     m.method == AaMethod::Fft ? fmt::format("{:.1f}", m.filter_ms) : "-", m.err.rmse, m.err.psnr,
                     m.err.max_abs, m.same_as_previous ? "bytes identical to the row above" : "");
  return s;
}

}  // namespace tessera::bench
