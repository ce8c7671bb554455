// The OpenGL view and projection of a Tessera Camera (docs/DESIGN.md "Camera": pixel centres, vertical
// fov or orthographic height, aspect W/H) with near/far from the scene bounds. Depth is reversed
// (near -> 1, far -> 0, glClipControl ZERO_TO_ONE, 32-bit float depth) so that a camera inside
// the mesh, whose near plane must be tiny, keeps its depth precision. Plain values.
#pragma once
#include <array>

#include "common/camera.h"
#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

struct ViewProjection {
  std::array<double, 16> view{}, proj{};  // column-major, as glUniformMatrix4fv takes them
  std::array<double, 16> mvp{};           // proj * view
  double near_plane = 0, far_plane = 0;   // along the view direction, world units
  bool orthographic = false;
  int width = 0, height = 0;              // the FULL image this projection is for
};

// Throws std::invalid_argument for an invalid camera or size. Every tile of one image must use
// the same ViewProjection (same bounds, same full size) for tiles to be bit-identical.
ViewProjection makeViewProjection(const Camera& cam, int width, int height, const Box& scene_bounds);

// Clip coordinates (x, y, z, w) of a world point.
std::array<double, 4> toClip(const ViewProjection& vp, const Vec3& p);

}  // namespace tessera::renderer
