#include "master/interaction.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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
  c.eye = c.target + (c.eye - c.target) * std::clamp(in.zoom, 0.2, 5.0);
  return c;
}

}  // namespace tessera::master
