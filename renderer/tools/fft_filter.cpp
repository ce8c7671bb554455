// FFT Gaussian low-pass (see fft_filter.h).
#include "renderer/tools/fft_filter.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tessera::renderer {

void lowPassFilter(Image8& img, double sigma) {
  if (!(sigma >= 0 && sigma <= 64))
    throw std::invalid_argument("lowPassFilter: sigma must be in [0, 64] pixels, got " + std::to_string(sigma));
  if (sigma == 0 || img.width == 0 || img.height == 0) return;
  const int pad = (int)std::ceil(4 * sigma) + 1;
  const int w = img.width + 2 * pad, h = img.height + 2 * pad, wc = w / 2 + 1;
  float* real = fftwf_alloc_real((size_t)w * h);
  fftwf_complex* freq = fftwf_alloc_complex((size_t)wc * h);
  // FFTW_ESTIMATE: planning must not cost more than the transform for one-off images.
  fftwf_plan fwd = fftwf_plan_dft_r2c_2d(h, w, real, freq, FFTW_ESTIMATE);
  fftwf_plan inv = fftwf_plan_dft_c2r_2d(h, w, freq, real, FFTW_ESTIMATE);
  // Gaussian transfer function exp(-2 pi^2 sigma^2 f^2), f in cycles per pixel; 1/(w h) undoes
  // FFTW's unnormalised round trip.
  std::vector<float> gx(wc), gy(h);
  const double a = 2 * std::numbers::pi * std::numbers::pi * sigma * sigma;
  for (int x = 0; x < wc; ++x) gx[x] = (float)std::exp(-a * std::pow((double)x / w, 2));
  for (int y = 0; y < h; ++y) {
    const double f = (double)(y <= h / 2 ? y : y - h) / h;
    gy[y] = (float)(std::exp(-a * f * f) / ((double)w * h));
  }
  std::vector<float> result((size_t)img.width * img.height * 4);
  for (int c = 0; c < 4; ++c) {
    for (int y = 0; y < h; ++y) {
      const int sy = std::clamp(y - pad, 0, img.height - 1);
      for (int x = 0; x < w; ++x) real[(size_t)y * w + x] = img.at(std::clamp(x - pad, 0, img.width - 1), sy)[c];
    }
    fftwf_execute(fwd);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < wc; ++x) {
        const float g = gx[x] * gy[y];
        freq[(size_t)y * wc + x][0] *= g;
        freq[(size_t)y * wc + x][1] *= g;
      }
    fftwf_execute(inv);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        result[4 * ((size_t)y * img.width + x) + c] = real[(size_t)(y + pad) * w + x + pad];
  }
  fftwf_destroy_plan(fwd);
  fftwf_destroy_plan(inv);
  fftwf_free(real);
  fftwf_free(freq);
  for (size_t p = 0; p < result.size(); p += 4) {
    const float alpha = std::clamp(std::nearbyint(result[p + 3]), 0.0f, 255.0f);
    img.px[p + 3] = (uint8_t)alpha;
    for (int c = 0; c < 3; ++c) img.px[p + c] = (uint8_t)std::clamp(std::nearbyint(result[p + c]), 0.0f, alpha);
  }
}

}  // namespace tessera::renderer
