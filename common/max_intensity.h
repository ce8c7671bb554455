// Maximum intensity projection (scene `blend: maximum`), as VTK's MAXIMUM_INTENSITY_BLEND and
// ParaView's "Maximum Intensity": a pixel shows the colour map at the largest value along its
// ray. In the farm a ray's pieces are merged by their maxima (exact, in any order) and only the
// merged value is mapped, so the farm's image is tessera-render's (the windows' rounding of
// sample positions aside: within the accuracy contract, to the bit in the tests' frames).
//
// Until it is mapped a ray's result is a "value pixel" (s, 0, 0, 1), s the largest value in
// [0, 1] (a valid premultiplied pixel, so it travels and crops as any piece does), or
// transparent black where no value reaches `floor()`: below it every value maps to transparent,
// so no piece needs to carry it. Values compare in the ray caster's 16-bit units (q = s * 65535).
//
// Minimum intensity projection (`blend: minimum`) is the maximum projection of the complement:
// a value pixel holds 1 - m, m the ray's smallest value, and is mapped by the colour map
// mirrored (its point at s moved to 1 - s). So pieces merge by their maxima here too (1 - m is
// largest where m is smallest), transparent pixels still lose to every value, and every stage
// that merges or maps a maximum projection does the minimum one unchanged.
#pragma once
#include <cstddef>
#include <cstdint>

#include "common/image.h"
#include "common/transfer_function.h"

namespace tessera {

class MaxIntensity {
 public:
  // `minimum`: the map of a minimum projection's complemented values (`tf` mirrored).
  explicit MaxIntensity(const TransferFunction& tf, bool minimum = false);
  // Smallest 16-bit value a ray must reach to be kept: values below it map to transparent
  // (alpha 0 up to the colour map's first opacity). UINT32_MAX when no value has opacity.
  uint32_t floorQ() const { return floor_q_; }
  double floor() const { return floor_; }
  // Value pixels to premultiplied RGBA, in place: colour and opacity of the map at s, the
  // opacity scaled so that the map's largest is 1 (a composite map's opacity is per 1/256 of
  // the box, 0.02 for the presets: as a pixel's it would hardly show). Transparent pixels stay.
  void map(float* rgba, size_t pixels) const;

 private:
  TransferFunction tf_;
  double floor_ = 0, alpha_scale_ = 0;
  uint32_t floor_q_ = 0;
};

// A farm stage's map for frames that may each show the colour map through another window (the
// user's window/level): made again when a frame's window differs from the last one's.
class WindowedMaxIntensity {
 public:
  WindowedMaxIntensity(TransferFunction tf, bool minimum) : tf_(std::move(tf)), minimum_(minimum), map_(tf_, minimum) {}
  const MaxIntensity& at(const ColorWindow& w) {
    if (!(w == window_)) map_ = MaxIntensity(windowed(tf_, w), minimum_), window_ = w;
    return map_;
  }

 private:
  TransferFunction tf_;
  bool minimum_;
  ColorWindow window_;
  MaxIntensity map_;
};

// tf with each point at s moved to 1 - s: mirrored(tf).eval(s) == tf.eval(1 - s), but at a
// step's own value, which takes the step's other side.
TransferFunction mirrored(const TransferFunction& tf);

// Value pixels merged: dst = max(dst, src) per channel, within rect r (same sizes).
void compositeMaximum(ImageF& dst, const ImageF& src, const Rect& r);

}  // namespace tessera
