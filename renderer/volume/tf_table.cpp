// Transfer-function lookup table (see tf_table.h).
#include "renderer/volume/tf_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tessera::renderer {

TfTable::TfTable(const TransferFunction& tf, double step) : entries_(kEntries), nonzero_(kEntries, 0) {
  if (!(step > 0) || !std::isfinite(step)) throw std::invalid_argument("TfTable: step must be positive and finite");
  const auto [lo, hi] = tf.variedSpan();
  scale_ = (float)(kEntries - 1) / (float)(hi - lo);
  offset_ = lo == 0 ? 0.0f : (float)(-lo * (kEntries - 1) / (hi - lo));
  for (int j = 0; j < kEntries; ++j) {
    const double s = lo + (hi - lo) * ((double)j / (kEntries - 1));
    const auto c = tf.eval(s);
    const double a = correctOpacity(c[3], step);
    entries_[j] = Entry{{(float)(a * c[0]), (float)(a * c[1]), (float)(a * c[2]), (float)a}};
  }
  for (int j = 0; j + 1 < kEntries; ++j) {
    nonzero_[j] = (entries_[j].v[3] > 0 || entries_[j + 1].v[3] > 0) ? 1 : 0;
    if (nonzero_[j]) first_nonzero_ = std::min(first_nonzero_, j), last_nonzero_ = j;
  }
}

void TfTable::lookup(float s, float out[4]) const {
  const float f = std::clamp(std::fma(s, scale_, offset_), 0.0f, (float)(kEntries - 1));
  const int i = std::min((int)f, kEntries - 2);
  const float w = f - (float)i;
  for (int c = 0; c < 4; ++c) {
    const float e0 = entries_[i].v[c], e1 = entries_[i + 1].v[c];
    out[c] = std::fma(w, e1 - e0, e0);
  }
}

bool TfTable::rangeIsEmpty(const TransferFunction& tf, float lo, float hi) {
  constexpr double kMargin = 2.0 / (kEntries - 1);
  return tf.maxAlpha(std::max(0.0, (double)lo - kMargin), std::min(1.0, (double)hi + kMargin)) <= 0.0;
}

}  // namespace tessera::renderer
