// Anti-aliasing of geometry judged by run time against error: none, MSAA 2/4,
// supersampling 2x2/3x3 and the FFT low-pass post filter at several sigmas, each against a
// 16x (4x4) supersampled render of the same view. One OSMesa context: not thread-safe.
#pragma once
#include <string>
#include <vector>

#include "common/image.h"
#include "common/scene.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/mesh_scene.h"

namespace tessera::bench {

struct AaRow {
  AaMethod method = AaMethod::None;
  int samples = 1;                // MSAA samples or SSAA factor k (k x k)
  double sigma = 0;               // fft: Gaussian sigma in pixels
  double ms = 0;                  // best of repeats: render + post filter
  double filter_ms = 0;           // fft: the post filter alone
  ImageError err;                 // vs the 16x reference, RGBA in [0,1]
  bool same_as_previous = false;  // bytes identical to the row before (MSAA 2 rendered as 4)
  std::string label() const;      // "msaa 4", "ssaa 3x3", "fft s=0.7"
};

struct AaSweepResult {
  std::vector<AaRow> rows;
  double reference_ms = 0;
  int width = 0, height = 0;
  size_t triangles = 0;
};

AaSweepResult aaSweep(renderer::GlRenderer& r, const renderer::SceneGeometry& g, const Camera& cam, int width,
                      int height, const renderer::GlRenderOptions& base, int repeat);

// CSV: method,samples,sigma,label,ms,filter_ms,rmse,psnr_db,max_abs.
void writeAaCsv(const std::string& path, const AaSweepResult& res);
// gnuplot PNG of RMSE and PSNR against time, one labelled point per method. Returns false
// (and says why on stderr) when gnuplot is missing or fails; the CSV stays valid.
bool plotAa(const std::string& csv_path, const std::string& png_path, const std::string& title);
std::string aaMarkdown(const AaSweepResult& res);

}  // namespace tessera::bench
