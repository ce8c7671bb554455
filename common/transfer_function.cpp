// Piecewise-linear transfer function and opacity correction (docs/DESIGN.md "Transfer function").
#include "common/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tessera {

TransferFunction::TransferFunction(std::vector<TfPoint> points) : points_(std::move(points)) {
  if (points_.empty()) throw std::invalid_argument("transfer function: no control points");
  for (size_t i = 0; i < points_.size(); ++i) {
    const TfPoint& p = points_[i];
    for (double v : {p.s, p.r, p.g, p.b, p.a}) {
      if (!(v >= 0.0 && v <= 1.0))  // NaN fails too
        throw std::invalid_argument("transfer function: point " + std::to_string(i) +
                                    ": values must be in [0, 1], got " + std::to_string(v));
    }
    // Equal scalars are allowed: they make a step (a jump in colour/opacity).
    if (i > 0 && p.s < points_[i - 1].s)
      throw std::invalid_argument("transfer function: point " + std::to_string(i) + ": scalar " +
                                  std::to_string(p.s) + " is less than the previous " +
                                  std::to_string(points_[i - 1].s) + " (points must be sorted)");
  }
}

std::array<double, 4> TransferFunction::eval(double s) const {
  if (points_.empty()) return {0, 0, 0, 0};
  auto rgba = [](const TfPoint& p) { return std::array<double, 4>{p.r, p.g, p.b, p.a}; };
  if (!(s > points_.front().s)) return rgba(points_.front());  // also catches NaN
  if (s >= points_.back().s) return rgba(points_.back());
  // First point with scalar > s; its predecessor has scalar <= s, and at a step the right value wins.
  auto it = std::upper_bound(points_.begin(), points_.end(), s,
                             [](double v, const TfPoint& p) { return v < p.s; });
  const TfPoint& b = *it;
  const TfPoint& a = *(it - 1);
  double t = (s - a.s) / (b.s - a.s);
  return {a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b), a.a + t * (b.a - a.a)};
}

double TransferFunction::maxAlpha(double lo, double hi) const {
  if (points_.empty()) return 0;
  if (lo > hi) std::swap(lo, hi);
  // Piecewise linear: the maximum is at an end point or at a control point inside [lo, hi].
  double m = std::max(eval(lo)[3], eval(hi)[3]);
  for (const TfPoint& p : points_)
    if (p.s >= lo && p.s <= hi) m = std::max(m, p.a);
  return m;
}

std::array<double, 2> TransferFunction::variedSpan() const {
  const auto& p = points_;
  if (p.empty()) return {0, 1};
  auto same = [](const TfPoint& a, const TfPoint& b) { return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a; };
  size_t i = 0, j = p.size() - 1;
  while (i < j && same(p[i + 1], p.front())) ++i;  // constant up to p[i]
  while (j > i && same(p[j - 1], p.back())) --j;   // and from p[j] on
  double lo = p[i].s, hi = p[j].s;
  if (!(hi - lo > 1e-6)) return {0, 1};
  // A step at the low end: eval gives its right-hand value there, so the span starts one table
  // entry below it (the values under the step went to entry 0 with the value above: found by review).
  if (p[i + 1].s == p[i].s) lo -= (hi - lo) / (kTfTableEntries - 2);
  // No finer than 16 steps of the 16-bit voxels, which resolve no more: a table position of a
  // far narrower span runs out of float digits (the GL shader's unfused multiply-add).
  if (constexpr double kFinest = 16.0 / 65535; hi - lo < kFinest) lo = (lo + hi - kFinest) / 2, hi = lo + kFinest;
  return {std::max(0.0, lo), std::min(1.0, hi)};
}

TransferFunction windowed(const TransferFunction& tf, const ColorWindow& w) {
  if (!std::isfinite(w.center) || !std::isfinite(w.width) || !(w.width > 0))
    throw std::invalid_argument("colour window: center " + std::to_string(w.center) + " and width " +
                                std::to_string(w.width) + " must be finite, the width positive");
  if (w.isDefault() || tf.points().empty()) return tf;
  auto at = [&](double s) {  // tf's point at window position s
    const auto c = tf.eval((s - w.center) / w.width + 0.5);
    auto unit = [](double v) { return std::clamp(v, 0.0, 1.0); };  // interpolation may round past an end
    return TfPoint{s, unit(c[0]), unit(c[1]), unit(c[2]), unit(c[3])};
  };
  std::vector<TfPoint> points{at(0)};
  for (TfPoint p : tf.points()) {
    p.s = w.center + (p.s - 0.5) * w.width;
    // A point moved onto 1 stays: a step there holds its left value up to 1 (at 0, at(0) is
    // the step's right value, which is what 0 shows).
    if (p.s > 0 && p.s <= 1) points.push_back(p);
  }
  points.push_back(at(1));
  return TransferFunction(std::move(points));
}

std::array<double, 2> windowRange(const std::array<double, 2>& range, const ColorWindow& w) {
  const double span = range[1] - range[0];
  return {range[0] + (w.center - w.width / 2) * span, range[0] + (w.center + w.width / 2) * span};
}

double correctOpacity(double alpha, double d) {
  if (alpha <= 0) return 0;
  if (alpha >= 1) return 1;
  // expm1/log1p keep precision when alpha is tiny and d/L0 is small or large.
  return -std::expm1(std::log1p(-alpha) * (d / kL0));
}

bool isCtPreset(const std::string& name) { return name == "ct-bone" || name == "ct-soft-tissue"; }

namespace {

// Points (HU, r, g, b, opacity) mapped to s over kCtRange.
TransferFunction inHounsfield(const std::vector<std::array<double, 5>>& hu) {
  std::vector<TfPoint> points;
  for (const auto& [v, r, g, b, a] : hu) points.push_back({(v - kCtRange[0]) / (kCtRange[1] - kCtRange[0]), r, g, b, a});
  return TransferFunction(std::move(points));
}

}  // namespace

TransferFunction transferFunctionPreset(const std::string& name) {
  if (name == "ct-bone")
    return inHounsfield({{-3024, 0, 0, 0, 0},
                         {150, 0.729412, 0.254902, 0.301961, 0},
                         {641.385, 0.905882, 0.815686, 0.552941, 0.715686},
                         {3071, 1, 1, 1, 0.705882}});
  if (name == "ct-soft-tissue")
    return inHounsfield({{-3024, 0, 0, 0, 0},
                         {-155.407, 0.54902, 0.25098, 0.14902, 0},
                         {217.641, 0.882353, 0.603922, 0.290196, 0.676471},
                         {419.736, 1, 0.937033, 0.954531, 0.833333},
                         {3071, 0.827451, 0.658824, 1, 0.803922}});
  // Colour control points (s, r, g, b); opacity is added as a linear ramp.
  using Stops = std::vector<std::array<double, 4>>;
  Stops stops;
  if (name == "cool-to-warm")  // Moreland, "Diverging Color Maps for Scientific Visualization" (2009)
    stops = {{0.0, 0.231, 0.298, 0.753}, {0.5, 0.865, 0.865, 0.865}, {1.0, 0.706, 0.016, 0.150}};
  else if (name == "viridis")  // matplotlib's viridis at five stops
    stops = {{0.0, 0.267, 0.005, 0.329},
             {0.25, 0.229, 0.322, 0.546},
             {0.5, 0.128, 0.567, 0.551},
             {0.75, 0.369, 0.789, 0.383},
             {1.0, 0.993, 0.906, 0.144}};
  else if (name == "grayscale")
    stops = {{0.0, 0.0, 0.0, 0.0}, {1.0, 1.0, 1.0, 1.0}};
  else
    throw std::invalid_argument("unknown transfer function preset '" + name + "' (cool-to-warm | viridis | grayscale | ct-bone | ct-soft-tissue)");
  std::vector<TfPoint> points;
  for (const auto& [sv, r, g, b] : stops) points.push_back({sv, r, g, b, kPresetOpacity * sv});
  return TransferFunction(std::move(points));
}

}  // namespace tessera
