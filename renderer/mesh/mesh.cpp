// Mesh utilities: bounds, smooth normals, unit-box fitting, validation, loading by extension.
#include "renderer/mesh/mesh.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tessera::renderer {

void Box::add(const Vec3& p) {
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::min(lo[i], p[i]);
    hi[i] = std::max(hi[i], p[i]);
  }
}

Box bounds(const Mesh& mesh) {
  Box b;
  for (size_t v = 0; v < mesh.vertexCount(); ++v)
    b.add({mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]});
  return b;
}

void computeSmoothNormals(Mesh& mesh) {
  std::vector<double> acc(mesh.positions.size(), 0.0);
  auto pos = [&](uint32_t v) {
    return Vec3{mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
  };
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    // The cross product's length is twice the area: larger faces weigh more.
    const Vec3 n = cross(pos(tri[1]) - pos(tri[0]), pos(tri[2]) - pos(tri[0]));
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) continue;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) acc[3 * tri[k] + c] += n[c];
  }
  mesh.normals.assign(mesh.positions.size(), 0.0f);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    Vec3 n{acc[3 * v], acc[3 * v + 1], acc[3 * v + 2]};
    const double len = length(n);
    n = (len > 0 && std::isfinite(len)) ? n * (1.0 / len) : Vec3{0, 0, 1};
    for (int c = 0; c < 3; ++c) mesh.normals[3 * v + c] = (float)n[c];
  }
}

void fitToUnitBox(Mesh& mesh) {
  const Box b = bounds(mesh);
  if (b.empty()) return;
  const Vec3 c = (b.lo + b.hi) * 0.5;
  const double extent = std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z});
  const double s = extent > 0 ? 1.0 / extent : 1.0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v)
    for (int i = 0; i < 3; ++i) mesh.positions[3 * v + i] = (float)((mesh.positions[3 * v + i] - c[i]) * s);
}

void validateMesh(const Mesh& mesh, const std::string& name) {
  const size_t n = mesh.vertexCount();
  if (mesh.positions.size() % 3 != 0 || mesh.normals.size() != mesh.positions.size() ||
      mesh.colors.size() != mesh.positions.size() || mesh.indices.size() % 3 != 0)
    throw std::runtime_error(name + ": mesh arrays disagree in size");
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!std::isfinite(mesh.positions[i]))
      throw std::runtime_error(name + ": vertex " + std::to_string(i / 3) + ": position is not finite");
  for (size_t i = 0; i < mesh.normals.size(); ++i)
    if (!std::isfinite(mesh.normals[i]) || !std::isfinite(mesh.colors[i]))
      throw std::runtime_error(name + ": vertex " + std::to_string(i / 3) + ": normal or colour is not finite");
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= n)
      throw std::runtime_error(name + ": triangle " + std::to_string(i / 3) + ": vertex index " +
                               std::to_string(mesh.indices[i]) + " out of range (" + std::to_string(n) +
                               " vertices)");
  if (mesh.triangleCount() == 0) throw std::runtime_error(name + ": empty mesh (no triangles)");
}

namespace {
std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open mesh file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

Mesh loadPly(const std::string& path) { return parsePly(readFile(path), path); }
Mesh loadObj(const std::string& path) { return parseObj(readFile(path), path); }

Mesh loadMesh(const std::string& path) {
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  if (ext == ".ply") return loadPly(path);
  if (ext == ".obj") return loadObj(path);
  throw std::runtime_error(path + ": unknown mesh format (expected .ply or .obj)");
}

}  // namespace tessera::renderer
