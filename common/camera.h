// Camera per docs/DESIGN.md: perspective (vertical fov, degrees) or orthographic (view height).
// The ray of pixel (px,py) passes through the pixel centre. Units are the unit-box scene units.
#pragma once
#include "common/vec.h"

namespace tessera {

struct Camera {
  Vec3 eye{0, 0, 2.5}, target{0, 0, 0}, up{0, 1, 0};
  double fov = 30;             // degrees, perspective
  bool orthographic = false;
  double height = 1;           // orthographic view height
  bool operator==(const Camera&) const = default;

  // Throws std::invalid_argument if eye == target, up is parallel to the view, fov not in (0,180).
  void validate() const;
  // Eye rotated about `axis` through target by `degrees`.
  Camera orbited(const Vec3& axis, double degrees) const;
};

// The camera ParaView's Reset Camera gives: looking at the centre of a box with these half
// extents from the front and a little above (from `front`, raised towards `up`: +z and +y
// unless the data says where its front is), far enough that the whole box fits the
// 30-degree view with a margin, across the narrower of the image's two sides
// (aspect = width / height).
Camera fittedCamera(const Vec3& half_extent, double aspect = 1.0, const Vec3& front = {0, 0, 1}, const Vec3& up = {0, 1, 0});

struct Ray {
  Vec3 origin, dir;  // dir normalized
};

// Precomputed basis so per-pixel rays are cheap.
class RayGenerator {
 public:
  RayGenerator(const Camera& cam, int width, int height);
  Ray ray(double px_centre_x, double px_centre_y) const;  // pass px+0.5, py+0.5
  Ray pixelRay(int px, int py) const { return ray(px + 0.5, py + 0.5); }
  // What ray() computes from, for code that makes many rays at once with the same arithmetic.
  struct Basis {
    Vec3 eye, fwd, right, up;
    double tan_half, aspect;
    int width, height;
    bool orthographic;
  };
  Basis basis() const { return {cam_.eye, fwd_, right_, upv_, tan_half_, aspect_, w_, h_, cam_.orthographic}; }
  // Screen-space projection of a world point to continuous pixel coords; false if behind eye.
  bool project(const Vec3& p, double& sx, double& sy) const;

 private:
  Camera cam_;
  int w_, h_;
  Vec3 fwd_, right_, upv_;
  double tan_half_, aspect_;
};

}  // namespace tessera
