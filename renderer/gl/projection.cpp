// View/projection matrices for the OSMesa backend (see projection.h).
#include "renderer/gl/projection.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tessera::renderer {

ViewProjection makeViewProjection(const Camera& cam, int width, int height, const Box& b) {
  cam.validate();
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("projection: image size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  ViewProjection vp;
  vp.width = width;
  vp.height = height;
  vp.orthographic = cam.orthographic;
  const Vec3 fwd = normalize(cam.target - cam.eye);
  const Vec3 right = normalize(cross(fwd, cam.up));
  const Vec3 upv = cross(right, fwd);
  const Vec3 rows[3] = {right, upv, fwd * -1.0};
  auto& v = vp.view;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) v[c * 4 + r] = rows[r][c];
    v[12 + r] = -dot(rows[r], cam.eye);
  }
  v[15] = 1;

  // Depth range of the scene box along the view direction: the extremes are at corners.
  double dmin = 1e300, dmax = -1e300;
  if (!b.empty())
    for (int c = 0; c < 8; ++c) {
      const Vec3 p{(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
      const double d = dot(p - cam.eye, fwd);
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
    }
  else
    dmin = dmax = 1;
  const double aspect = (double)width / height;
  auto& p = vp.proj;
  if (cam.orthographic) {
    const double margin = 0.01 * (dmax - dmin) + 1e-6 * std::max(std::fabs(dmin), std::fabs(dmax)) + 1e-12;
    vp.near_plane = dmin - margin;
    vp.far_plane = dmax + margin;
    const double n = vp.near_plane, f = vp.far_plane, hh = cam.height * 0.5;
    p[0] = 1 / (aspect * hh);
    p[5] = 1 / hh;
    p[10] = 1 / (f - n);  // z_ndc = 1 at -n, 0 at -f
    p[14] = f / (f - n);
    p[15] = 1;
  } else {
    double f = dmax * 1.01;
    if (!(f > 0)) f = 1;  // everything is behind the eye: any valid range draws nothing
    // Outside the box: just before its nearest point; inside: a tiny fraction of the far plane.
    double n = dmin > 0 ? dmin * 0.99 : f * 1e-6;
    n = std::max(n, f * 1e-6);
    vp.near_plane = n;
    vp.far_plane = f;
    const double t = std::tan(cam.fov * std::numbers::pi / 360.0);
    p[0] = 1 / (aspect * t);
    p[5] = 1 / t;
    p[10] = n / (f - n);  // reversed: z_ndc = 1 at -n, 0 at -f
    p[11] = -1;
    p[14] = n * f / (f - n);
  }
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += p[k * 4 + r] * v[c * 4 + k];
      vp.mvp[c * 4 + r] = s;
    }
  return vp;
}

std::array<double, 4> toClip(const ViewProjection& vp, const Vec3& p) {
  std::array<double, 4> out{};
  for (int r = 0; r < 4; ++r)
    out[r] = vp.mvp[r] * p.x + vp.mvp[4 + r] * p.y + vp.mvp[8 + r] * p.z + vp.mvp[12 + r];
  return out;
}

}  // namespace tessera::renderer
