// Camera validation, orbiting and per-pixel ray generation (docs/DESIGN.md "Camera").
#include "common/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tessera {

namespace {
bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Rodrigues rotation of v about the unit axis k.
Vec3 rotate(const Vec3& v, const Vec3& k, double radians) {
  double c = std::cos(radians), s = std::sin(radians);
  return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}
}  // namespace

void Camera::validate() const {
  if (!finite(eye) || !finite(target) || !finite(up))
    throw std::invalid_argument("camera: eye, target and up must be finite");
  if (!std::isfinite(fov) || !std::isfinite(height))
    throw std::invalid_argument("camera: fov and height must be finite");
  Vec3 view = target - eye;
  double vl = length(view);
  if (!(vl > 0)) throw std::invalid_argument("camera: eye equals target (no view direction)");
  double ul = length(up);
  if (!(ul > 0)) throw std::invalid_argument("camera: up vector is zero");
  // Relative test so that tiny and huge scene scales behave alike.
  if (length(cross(view, up)) <= 1e-9 * vl * ul)
    throw std::invalid_argument("camera: up is parallel to the view direction");
  if (orthographic) {
    if (!(height > 0))
      throw std::invalid_argument("camera: orthographic height must be > 0, got " + std::to_string(height));
  } else if (!(fov > 0 && fov < 180)) {
    throw std::invalid_argument("camera: fov must be in (0, 180) degrees, got " + std::to_string(fov));
  }
}

Camera Camera::orbited(const Vec3& axis, double degrees) const {
  double al = length(axis);
  if (!(al > 0) || !std::isfinite(al)) throw std::invalid_argument("camera: orbit axis must be non-zero");
  Vec3 k = axis * (1.0 / al);
  double rad = degrees * std::numbers::pi / 180.0;
  Camera c = *this;
  c.eye = target + rotate(eye - target, k, rad);
  c.up = rotate(up, k, rad);  // rigid motion: keeps up non-parallel to the view
  return c;
}

RayGenerator::RayGenerator(const Camera& cam, int width, int height) : cam_(cam), w_(width), h_(height) {
  cam.validate();
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("RayGenerator: image size must be positive, got " + std::to_string(width) +
                                "x" + std::to_string(height));
  fwd_ = normalize(cam.target - cam.eye);
  right_ = normalize(cross(fwd_, cam.up));
  upv_ = cross(right_, fwd_);
  aspect_ = (double)width / height;
  tan_half_ = cam.orthographic ? cam.height * 0.5 : std::tan(cam.fov * std::numbers::pi / 360.0);
}

Ray RayGenerator::ray(double cx, double cy) const {
  // tan_half_ is the half view height at unit distance (perspective) or absolutely (ortho).
  double x = (2.0 * cx / w_ - 1.0) * aspect_ * tan_half_;
  double y = (1.0 - 2.0 * cy / h_) * tan_half_;
  if (cam_.orthographic) return Ray{cam_.eye + right_ * x + upv_ * y, fwd_};
  return Ray{cam_.eye, normalize(fwd_ + right_ * x + upv_ * y)};
}

bool RayGenerator::project(const Vec3& p, double& sx, double& sy) const {
  Vec3 d = p - cam_.eye;
  double z = dot(d, fwd_);
  double x = dot(d, right_), y = dot(d, upv_);
  if (!cam_.orthographic) {
    if (!(z > 0)) return false;
    x /= z;
    y /= z;
  }
  // Inverse of ray(): continuous pixel coordinates, (0,0) top-left corner of the image.
  sx = (x / (aspect_ * tan_half_) + 1.0) * 0.5 * w_;
  sy = (1.0 - y / tan_half_) * 0.5 * h_;
  // Orthographic rays start on the plane through the eye; points behind it are not seen.
  return !cam_.orthographic || z >= 0;
}

Camera fittedCamera(const Vec3& half_extent, double aspect, const Vec3& front, const Vec3& up) {
  Camera c;
  const double radius = length(half_extent);  // the box's bounding sphere
  // The fov is vertical; a portrait image sees less across (tan scales with the aspect).
  const double half_angle = std::atan(std::min(1.0, aspect) * std::tan(c.fov / 2 * std::numbers::pi / 180));
  const double distance = 1.05 * radius / std::sin(half_angle);
  c.eye = normalize(normalize(front) + normalize(up) * 0.3) * distance;
  c.up = normalize(up);
  c.target = {0, 0, 0};
  return c;
}

}  // namespace tessera
