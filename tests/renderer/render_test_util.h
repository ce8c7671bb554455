// Shared helpers for the renderer tests: small volumes, the default transfer function,
// finiteness checks and a diff dump for failing image comparisons.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

#include "common/image.h"
#include "common/io/image_io.h"
#include "tests/common/image_dump.h"
#include "common/scene.h"
#include "common/volume.h"
#include "renderer/volume/raycaster.h"
#include "renderer/volume/tf_table.h"

namespace tessera::renderer::test {

inline std::shared_ptr<const Volume> generated(const std::string& name, int size, std::array<double, 3> spacing = {1, 1, 1}) {
  return std::make_shared<const Volume>(generateVolume(GeneratorSpec{name, size, 1, spacing}));
}

inline std::shared_ptr<const Volume> constant(std::array<int, 3> dims, float value, std::array<double, 3> spacing = {1, 1, 1}) {
  auto v = std::make_shared<Volume>();
  v->dims = dims;
  v->spacing = spacing;
  v->values.assign(v->voxelCount(), value);
  return v;
}

// One slice, 48 x 40, a hundredth of a step thick (spacing 0.05 across): values rise along x.
inline std::shared_ptr<const Volume> slice() {
  auto v = std::make_shared<Volume>();
  v->dims = {48, 40, 1};
  v->spacing = {1, 1, 0.05};
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) v->values.push_back(0.2f + 0.8f * x / 47 * (0.5f + 0.5f * (y % 8 < 4)));
  return v;
}
// Opaque at the top of the range, so a slice shows.
inline TransferFunction opaqueTf() { return TransferFunction({{0, 0, 0, 1, 0}, {1, 1, 0.3, 0, 1}}); }

inline TransferFunction defaultTf() { return defaultScene().tf; }
inline Camera defaultCamera() { return defaultScene().camera; }

inline RenderOptions options(const std::string& quality, int threads = 0) {
  RenderOptions o;
  o.quality = namedQuality(quality);
  o.threads = threads;
  return o;
}

// The largest error of tab's lookup against tf evaluated exactly (opacity-corrected for kL0,
// premultiplied), over n + 1 scalars from lo to hi, each as the float the table is given.
inline double tableError(const TfTable& tab, const TransferFunction& tf, double lo, double hi, int n) {
  double worst = 0;
  for (int i = 0; i <= n; ++i) {
    const float s = (float)(lo + (hi - lo) * i / n);
    const auto c = tf.eval(s);
    const double a = correctOpacity(c[3], kL0);
    float out[4];
    tab.lookup(s, out);
    for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, std::abs(out[ch] - a * c[ch]));
    worst = std::max(worst, std::abs(out[3] - a));
  }
  return worst;
}

inline bool allFinite(const ImageF& img) {
  for (float v : img.px)
    if (!std::isfinite(v) || v < 0.0f || v > 1.0f + 1e-5f) return false;
  return true;
}

// Writes expected, actual and difference PNGs and returns their paths (for failure messages).
inline std::string dumpImages(const std::string& name, const ImageF& expected, const ImageF& actual) {
  return tessera::test::writeImageMismatch(std::filesystem::path(TESSERA_BINARY_DIR) / "test-output" / "renderer", name,
                                           toRGBA8(expected), toRGBA8(actual));
}

}  // namespace tessera::renderer::test
