// Piecewise-linear RGBA transfer function over the normalised scalar in [0,1].
// Colours are linear RGB; alpha is opacity per reference length L0 = 1/256 of the unit box.
#pragma once
#include <array>
#include <string>
#include <vector>

namespace tessera {

inline constexpr double kL0 = 1.0 / 256.0;
// The fast kernels sample a map at this many scalars over its varied span (renderer TfTable).
inline constexpr int kTfTableEntries = 4096;

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
  // Where the map varies: [0, 1], or less where it is constant up to or from an end (below and
  // above a colour window, say), starting a table entry below a step at its low end and at
  // least 16/65535 wide; [0, 1] for a constant map or a step at one scalar.
  std::array<double, 2> variedSpan() const;
  bool operator==(const TransferFunction&) const = default;

 private:
  std::vector<TfPoint> points_;
};

// The colour map's window, as a CT viewer's window/level and ParaView's "rescale to custom
// range" set it: the map's [0, 1] laid over [center - width/2, center + width/2] of the
// normalised values (below and above it the map's end colours, as outside the range). The
// default is the map as the scene gives it. A window is a change of the scene's `range`
// (windowRange) done on the map instead of the voxels, so renderers keep their voxels.
struct ColorWindow {
  // The largest |center| and width a frame may carry (FrameParams): far beyond the values.
  static constexpr double kLimit = 1e6;
  double center = 0.5, width = 1;
  bool isDefault() const { return center == 0.5 && width == 1; }
  bool operator==(const ColorWindow&) const = default;
};
// tf seen through w: windowed(tf, w).eval(s) == tf.eval((s - center) / width + 0.5) for s in
// [0, 1], to rounding. Its points: tf's moved into the window, those outside [0, 1] replaced by
// the map's values at 0 and 1. Throws std::invalid_argument unless width > 0 and both are finite.
TransferFunction windowed(const TransferFunction& tf, const ColorWindow& w);
// The data range a scene's `range` gives for window w of the mapped range lo..hi.
std::array<double, 2> windowRange(const std::array<double, 2>& range, const ColorWindow& w);

// Opacity correction for a step of length d: a = 1 - (1 - alpha)^(d / L0).
double correctOpacity(double alpha, double d);

// The colour maps a scene may name instead of listing points (`transfer_function: viridis`),
// each with opacity rising linearly from 0 at the range's low end to kPresetOpacity at its
// high end, as ParaView's default opacity ramp does. Opacity is per L0 = 1/256 of the box:
// 0.02 lets a ray cross the whole box at the top value and keep 1 - 0.98^256 = 99.4% of it,
// so the outer values veil the inner ones without hiding them:
//   cool-to-warm  (the default) Moreland's diverging map, ParaView's default
//   viridis       perceptually uniform (van der Walt and Smith, matplotlib 2.0)
//   grayscale     black to white
// Throws std::invalid_argument naming the word and the choices.
// Also the CT presets below.
inline constexpr double kPresetOpacity = 0.02;
TransferFunction transferFunctionPreset(const std::string& name);

// Colour maps in Hounsfield units for CT, after 3D Slicer's volume-rendering presets: their
// points in HU over kCtRange (which they set as the volume's range), their opacities taken
// as opacity per 1/256 of the box (those presets also shade: give `shading: true`):
//   ct-bone         Slicer's CT-Bone colours, its opacity starting at 150 HU instead of -16
//                   (Slicer's own makes soft tissue, 40 HU, a red wall in front of the bones)
//   ct-soft-tissue  muscle and skin, bone bright (Slicer's CT-Muscle)
inline constexpr std::array<double, 2> kCtRange{-3024, 3071};
bool isCtPreset(const std::string& name);

}  // namespace tessera
