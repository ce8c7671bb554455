// Warnings about a scene's volume (see scene_warnings.h).
#include "common/scene_warnings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>

#include "common/transfer_function.h"

namespace tessera {

namespace {

// Opacity counts per L0 (1/256 of the box's largest side), so a volume a few L0 thick gathers
// little of it on a ray straight across: a slice at the presets' 0.02 shows 2%.
std::string thinProblem(const Scene& scene, const Volume& shape) {
  const Vec3 h = shape.halfExtent();
  const double half[3] = {h.x, h.y, h.z};
  const int axis = (int)(std::min_element(half, half + 3) - half);
  const double thickness = 2 * half[axis] / kL0;  // in L0
  const double alpha = scene.tf.maxAlpha(0, 1);
  const double across = 1 - std::pow(1 - std::min(alpha, 1.0), thickness);
  if (thickness >= 8 || across >= 0.5) return "";
  char b[400];
  std::snprintf(b, sizeof b,
                "volume: %d voxel%s thick along %c, %.3g/256 of the box's largest side: opacity counts per 1/256 of "
                "that side, so a ray straight across gathers at most %.0f%% (the transfer function's highest opacity "
                "is %g) and the image is faint; give transfer_function points more opacity (`a` up to 1)",
                shape.dims[axis], shape.dims[axis] == 1 ? "" : "s", "xyz"[axis], thickness, 100 * across, alpha);
  return b;
}

// A microscope image's background (a camera's offset and its noise): one peak at the low end
// holding most voxels, which the transfer function gives enough opacity that, seen through
// the whole volume, it is a haze over the signal. The advice starts the range where the peak
// has fallen to 1% of its height. (CT's air is such a peak too, but the presets give it no
// opacity.) `tf` maps h.lo..h.hi to 0..1, as it does with no `range`.
std::optional<RangeAdvice> backgroundHaze(const ValueHistogram& h, const TransferFunction& tf) {
  const std::vector<uint64_t>& c = h.counts;
  const uint64_t total = h.total();
  const size_t n = c.size();
  if (total == 0 || !(h.hi > h.lo) || n < 64) return std::nullopt;
  // Heights over w bins: integers spanning fewer values than bins leave bins between them
  // empty (8-bit data: 15 of every 16), so a window holds at least two values.
  const size_t w = std::max<size_t>(8, h.integral ? 2 * (size_t)std::ceil(n / (h.hi - h.lo + 1)) : 8);
  if (w > n / 8) return std::nullopt;
  auto height = [&](size_t b) { return std::accumulate(c.begin() + (long)b, c.begin() + (long)std::min(n, b + w), uint64_t{0}); };
  size_t mode = 0;
  uint64_t peak = height(0);
  for (size_t b = 1; b + w <= n; ++b)
    if (const uint64_t hb = height(b); hb > peak) mode = b, peak = hb;
  if (mode >= n / 5) return std::nullopt;
  size_t end = mode + 1;
  while (end < n / 2 && 100 * height(end) >= peak) ++end;
  uint64_t held = 0;
  for (size_t b = 0; b < end; ++b) held += c[b];
  if (2 * held < total || end >= n / 2) return std::nullopt;  // not most voxels, or no end to the peak
  // Opacity per 1/256 of the box: over a ray across it (256 of them) 0.0004 gathers 10%.
  const double alpha = tf.maxAlpha(0, (double)end / n);
  if (alpha < 4e-4) return std::nullopt;
  const auto [a, b] = std::array<double, 2>{h.integral ? std::ceil(h.edge(end)) : h.edge(end), h.hi};
  char why[300];
  std::snprintf(why, sizeof why,
                "%.0f%% of the voxels lie in one peak at the low end, %.*g .. %.*g (a background?), where the transfer "
                "function's opacity reaches %.2g: seen through the volume it is a haze over the rest",
                100.0 * held / total, digitsToTell(h.lo, a), h.lo, digitsToTell(h.lo, a), a, alpha);
  return RangeAdvice{{a, b}, 1.0 - (double)held / total, why};
}

// A `window` beside every value the voxels keep (the mapped range clamps them before any
// window) shows each voxel in one end colour; one narrower than 1/256 of the mapped range
// shows in coarse steps (the casters' 16-bit voxels resolve the range, not the window).
std::string windowProblem(const Scene& scene, const Volume& shape) {
  if (!scene.window) return "";
  const ValueWindow& w = *scene.window;
  const auto [mlo, mhi] = shape.mapped_range;
  const double vlo = std::max(shape.data_range[0], mlo), vhi = std::min(shape.data_range[1], mhi);
  const bool clipped = vlo != shape.data_range[0] || vhi != shape.data_range[1];
  char b[500];
  if (vlo <= vhi && (w.hi() < vlo || w.lo() > vhi))
    std::snprintf(b, sizeof b, "window: level %.9g, width %.9g spans %.9g .. %.9g, none of the volume's values %.9g .. %.9g%s: "
                  "every voxel takes the colour map's %s end%s", w.level, w.width, w.lo(), w.hi(), vlo, vhi,
                  clipped ? " (as volume.range clamps them)" : "", w.hi() < vlo ? "top" : "bottom",
                  clipped ? "; widen volume.range or leave it out" : "");
  else if (vlo < vhi && w.width < (mhi - mlo) / 256)
    std::snprintf(b, sizeof b, "window: width %.9g is under 1/256 of the mapped range %.9g .. %.9g: the colour map shows "
                  "in coarse steps; give volume.range closer to the window", w.width, mlo, mhi);
  else
    return "";
  return b;
}

// The fast kernels sample the map at kTfTableEntries scalars over where it varies: an opacity
// peak narrower than two of those steps may show faint or not at all (a 0.0002-wide isovalue
// spike vanished: found by review). The reference quality evaluates the map exactly.
std::string narrowPeakProblem(const Scene& scene, const Volume& shape) {
  if (scene.blend != Blend::Composite || scene.quality.reference) return "";
  const TransferFunction tf = windowed(scene.tf, colorWindow(scene, shape.mapped_range));
  const auto [lo, hi] = tf.variedSpan();
  const double step = (hi - lo) / (kTfTableEntries - 1);
  const auto& p = tf.points();
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    size_t j = i;  // a peak: points i..j of one opacity (a plateau, or one point), lower on both sides
    while (j + 1 < p.size() && p[j + 1].a == p[i].a) ++j;
    if (j + 1 >= p.size() || !(p[i].a > p[i - 1].a && p[j].a > p[j + 1].a) || p[j + 1].s - p[i - 1].s >= 2 * step) continue;
    char b[400];
    std::snprintf(b, sizeof b, "transfer_function: the opacity peak at %.6g of the map is %.3g wide, under two steps "
                  "(%.3g) of the table the fast kernels sample it at: it may show faint or not at all; widen it, or "
                  "give quality: reference", p[i].s, p[j + 1].s - p[i - 1].s, 2 * step);
    return b;
  }
  return "";
}

}  // namespace

std::string rangeSuggestion(const Scene& scene, const ValueHistogram& fine) {
  const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume);
  // A scene's `window` already says which values the map spans; a range would only clip them.
  if (!raw || raw->has_range || scene.window) return "";
  auto advice = suggestedRange(fine);
  // A haze is opacity summed along rays; a maximum intensity projection sums none.
  if (!advice && scene.blend == Blend::Composite) advice = backgroundHaze(fine, scene.tf);
  if (!advice) return "";
  // Digits enough to tell the ends apart: a range printed as [1e+09, 1e+09] is refused.
  const int d = std::max(digitsToTell(fine.lo, fine.hi), digitsToTell(advice->range[0], advice->range[1]));
  char b[700];
  std::snprintf(b, sizeof b,
                "%s: volume: %s; with no `range` the transfer function spans the data's whole %.*g .. %.*g: "
                "`range: [%.*g, %.*g]` (%.3g%% of the voxels) spends it on the rest (values outside clamp to its ends)",
                scene.path.empty() ? "<default scene>" : scene.path.c_str(), advice->why.c_str(), d, fine.lo, d, fine.hi,
                d, advice->range[0], d, advice->range[1], 100 * advice->inside);
  return b;
}

std::vector<std::string> volumeWarnings(const Scene& scene, const Volume& shape) {
  const std::string where = (scene.path.empty() ? std::string("<default scene>") : scene.path) + ": ";
  std::vector<std::string> out;
  if (std::string why = rangeProblem(shape); !why.empty()) {
    const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume);
    out.push_back(where + (raw && raw->has_range ? "volume.range: " : "volume: ") + why);
  }
  if (std::string why = windowProblem(scene, shape); !why.empty()) out.push_back(where + why);
  if (std::string why = narrowPeakProblem(scene, shape); !why.empty()) out.push_back(where + why);
  // A minimum over a whole volume is, for most rays, the background around the object (a CT's
  // air): the image shows that one value's colour.
  if (scene.blend == Blend::Minimum && scene.crop.whole())
    out.push_back(where + "blend: minimum over the whole volume: most rays' smallest value is the background's "
                          "around the object (a scan's air), so most pixels show its colour; crop a slab of the "
                          "inside (`crop`, e.g. crop: {z: [0.4, 0.6]}) and look through it, as scenes/minip.yaml does");
  // A thin stack is faint when opacity adds up along few samples; a projection's is scaled to 1.
  if (scene.blend == Blend::Composite)
    if (std::string why = thinProblem(scene, shape); !why.empty()) out.push_back(where + why);
  if (const auto* raw = std::get_if<RawVolumeSpec>(&scene.volume)) {
    for (const std::string& note : raw->notes) out.push_back(where + "volume: " + note);
    std::string lacks;
    for (int a = 0; a < 3; ++a)
      if (!raw->spacing_known[a]) lacks += std::string(lacks.empty() ? "" : ", ") + "xyz"[a];
    if (!lacks.empty() && !raw->spacing_given)
      out.push_back(where + "volume: " + raw->file + " gives no voxel spacing along " + lacks +
                    ": 1 assumed there, so the volume's proportions may be wrong; give volume.spacing: [x, y, z]");
  }
  return out;
}

}  // namespace tessera
