#include "master/interaction.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "common/scene.h"

namespace tessera::master {

Camera applyInput(const Camera& cam, const proto::Input& in) {
  if (!std::isfinite(in.orbit_dx) || !std::isfinite(in.orbit_dy) || !std::isfinite(in.zoom) || in.zoom <= 0)
    throw std::invalid_argument("Input with non-finite or non-positive values");
  if (in.orbit_dx == 0 && in.orbit_dy == 0 && in.zoom == 1) return cam;  // exactly: a release moves nothing
  Camera c = cam.orbited(cam.up, -in.orbit_dx);  // drag right: the scene turns right
  Vec3 right = normalize(cross(c.target - c.eye, c.up));
  Camera tilted = c.orbited(right, -in.orbit_dy);
  try {
    tilted.validate();
    c = tilted;
  } catch (const std::invalid_argument&) {
    // up would be parallel to the view: keep the orbit, drop the tilt
  }
  // Each step scales the distance by 0.2..5, and the distance stays within the scene file's
  // limits: an eye zoomed out past them overflowed the view direction, every later input
  // threw, and every frame failed. A step that would leave the limits stops just inside them
  // (1e-12 inside: the new eye's rounding must not land it outside); one that would take an
  // eye coordinate past the limit (a target far off the origin) is not taken.
  const Vec3 away = c.eye - c.target;
  const double d = length(away);
  const double lo = kMinCameraDistance * (1 + 1e-12), hi = kMaxCameraDistance * (1 - 1e-12);
  Camera zoomed = c;
  zoomed.eye = c.target + away * (std::clamp(d * std::clamp(in.zoom, 0.2, 5.0), lo, hi) / d);
  if (cameraProblem(zoomed).what.empty()) c = zoomed;
  return c;
}

std::string windowNote(const Scene& scene, const ColorWindow& w) {
  const auto [lo, hi] = windowRange(mappedRange(scene), w);
  std::string note = fmt::format("colour window: the colour map spans the values {:.9g} to {:.9g}", lo, hi);
  if (w == colorWindow(scene)) return note + ", as the scene gives it";
  return note + fmt::format("; to keep it, give the scene `window: {{level: {:.9g}, width: {:.9g}}}`", (lo + hi) / 2, hi - lo);
}

}  // namespace tessera::master
