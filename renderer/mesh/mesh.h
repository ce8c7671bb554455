// Triangle meshes for the OSMesa backend: per-vertex position, normal and colour (float),
// triangle indices. Loaders throw std::runtime_error naming the file and the line or element.
// Plain values; not thread-safe for concurrent writes.
#pragma once
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/vec.h"

namespace tessera::renderer {

inline constexpr float kDefaultMeshColor[3] = {0.85f, 0.85f, 0.85f};

struct Mesh {
  std::vector<float> positions;  // x y z per vertex
  std::vector<float> normals;    // x y z per vertex (unit length, or zero if undefined)
  std::vector<float> colors;     // r g b per vertex, linear [0,1]
  std::vector<uint32_t> indices; // 3 per triangle
  size_t vertexCount() const { return positions.size() / 3; }
  size_t triangleCount() const { return indices.size() / 3; }
};

struct Box {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  bool empty() const { return lo.x > hi.x; }
  void add(const Vec3& p);
};

Box bounds(const Mesh& mesh);
// Area-weighted smooth normals; vertices of only degenerate triangles get (0,0,1).
void computeSmoothNormals(Mesh& mesh);
// Centres the mesh at the origin and scales it so the largest extent is 1 (the volumes' unit box).
void fitToUnitBox(Mesh& mesh);
// Throws std::runtime_error "<name>: ..." for: array sizes that disagree, non-finite positions
// (first vertex named), indices out of range (first triangle named), no triangles.
void validateMesh(const Mesh& mesh, const std::string& name);

// Positions as a file gives them (doubles) kept as floats relative to its first vertex: a mesh
// far from the origin (georeferenced or CAD data, 5e6 away) keeps its shape, where floats of
// the absolute coordinates (steps of 0.5 there) made a sphere of radius 1 a cluster of cubes
// (found by review). fitToUnitBox then centres it.
class RelativePositions {
 public:
  // False, adding nothing, for a vertex beyond a float's range (3e38) of the first one.
  bool add(std::vector<float>& out, const double v[3]) {
    if (!set_) origin_ = {v[0], v[1], v[2]}, set_ = true;
    for (int k = 0; k < 3; ++k)
      if (!(std::fabs(v[k] - origin_[k]) <= 3e38)) return false;
    for (int k = 0; k < 3; ++k) out.push_back((float)(v[k] - origin_[k]));
    return true;
  }

 private:
  std::array<double, 3> origin_{};
  bool set_ = false;
};

// Loaders. Missing normals are computed, missing colours are kDefaultMeshColor; the result is
// validated. loadMesh dispatches on the extension (.ply or .obj, case-insensitive).
Mesh loadPly(const std::string& path);
Mesh loadObj(const std::string& path);
Mesh loadMesh(const std::string& path);
// From text, for tests: `name` only labels errors.
Mesh parsePly(const std::string& bytes, const std::string& name);
Mesh parseObj(const std::string& text, const std::string& name);

}  // namespace tessera::renderer
