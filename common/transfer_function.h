// Piecewise-linear RGBA transfer function over the normalised scalar in [0,1].
// Colours are linear RGB; alpha is opacity per reference length L0 = 1/256 of the unit box.
#pragma once
#include <array>
#include <vector>

namespace tessera {

inline constexpr double kL0 = 1.0 / 256.0;

struct TfPoint {
  double s, r, g, b, a;
  bool operator==(const TfPoint&) const = default;
};

class TransferFunction {
 public:
  TransferFunction() = default;
  // Throws std::invalid_argument if points are empty, unsorted, or any value outside [0,1].
  explicit TransferFunction(std::vector<TfPoint> points);

  // Exact piecewise-linear evaluation (clamped to the end points outside their range).
  std::array<double, 4> eval(double s) const;
  // Largest alpha over scalars in [lo, hi] (exact: checks the end points and control points inside).
  double maxAlpha(double lo, double hi) const;
  const std::vector<TfPoint>& points() const { return points_; }
  bool operator==(const TransferFunction&) const = default;

 private:
  std::vector<TfPoint> points_;
};

// Opacity correction for a step of length d: a = 1 - (1 - alpha)^(d / L0).
double correctOpacity(double alpha, double d);

}  // namespace tessera
