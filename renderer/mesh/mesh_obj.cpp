// Wavefront OBJ reader: v (optionally with r g b), vn, f with v, v/vt, v/vt/vn and v//vn
// corners and negative (relative) indices; polygons fan-triangulated; other statements ignored.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

namespace {

// Resolves a 1-based (or negative, relative) OBJ index against `count` items; -1 if out of range.
long long resolve(long long idx, size_t count) {
  if (idx > 0 && (size_t)idx <= count) return idx - 1;
  if (idx < 0 && (size_t)(-idx) <= count) return (long long)count + idx;
  return -1;
}

}  // namespace

Mesh parseObj(const std::string& text, const std::string& name) {
  std::vector<float> pos, col, nrm;

  // Face corners as (position, normal) pairs; the normal is -1 when the corner has none.
  std::vector<std::pair<long long, long long>> corners;
  bool all_normals = true;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& msg) {
    throw std::runtime_error(name + ": line " + std::to_string(line_no) + ": " + msg);
  };
  auto numbers = [&](std::istringstream& ls, int min, int max) {
    std::vector<double> v;
    std::string tok;
    while (ls >> tok) {
      char* stop = nullptr;
      const double d = std::strtod(tok.c_str(), &stop);
      if (stop != tok.c_str() + tok.size()) fail("expected a number, got '" + tok + "'");
      v.push_back(d);
    }
    if ((int)v.size() < min || (int)v.size() > max)
      fail("expected " + std::to_string(min) + (min == max ? "" : ".." + std::to_string(max)) + " numbers, got " +
           std::to_string(v.size()));
    return v;
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string kw;
    if (!(ls >> kw) || kw[0] == '#') continue;
    if (kw == "v") {
      const auto v = numbers(ls, 3, 7);  // x y z [w] or x y z r g b
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(v[k]) || std::fabs(v[k]) > 3e38) fail("vertex position is not finite");
        pos.push_back((float)v[k]);
      }
      const bool has_rgb = v.size() >= 6;

      for (int k = 0; k < 3; ++k)
        col.push_back(has_rgb ? (float)std::clamp(v[3 + k], 0.0, 1.0) : kDefaultMeshColor[k]);
    } else if (kw == "vn") {
      const auto v = numbers(ls, 3, 3);
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(v[k])) fail("normal is not finite");
        nrm.push_back((float)v[k]);
      }
    } else if (kw == "f") {
      std::vector<std::pair<long long, long long>> poly;
      std::string tok;
      while (ls >> tok) {
        long long vi = 0, ni = 0;
        const size_t s1 = tok.find('/');
        const size_t s2 = s1 == std::string::npos ? std::string::npos : tok.find('/', s1 + 1);
        try {
          size_t used = 0;
          const std::string vs = tok.substr(0, s1);
          vi = std::stoll(vs, &used);
          if (used != vs.size()) throw std::invalid_argument(tok);
          if (s2 != std::string::npos && s2 + 1 < tok.size()) {
            const std::string ns = tok.substr(s2 + 1);
            ni = std::stoll(ns, &used);
            if (used != ns.size()) throw std::invalid_argument(tok);
          }
        } catch (const std::exception&) {
          fail("bad face corner '" + tok + "'");
        }
        const long long v = resolve(vi, pos.size() / 3);
        if (v < 0)
          fail("vertex index " + std::to_string(vi) + " out of range (" + std::to_string(pos.size() / 3) +
               " vertices so far)");
        long long n = -1;
        if (ni != 0) {
          n = resolve(ni, nrm.size() / 3);
          if (n < 0)
            fail("normal index " + std::to_string(ni) + " out of range (" + std::to_string(nrm.size() / 3) +
                 " normals so far)");
        }
        all_normals = all_normals && n >= 0;
        poly.emplace_back(v, n);
      }
      if (poly.size() < 3) fail("a face needs at least 3 vertices, got " + std::to_string(poly.size()));
      for (size_t k = 1; k + 1 < poly.size(); ++k) corners.insert(corners.end(), {poly[0], poly[k], poly[k + 1]});
    }
    // vt, o, g, s, usemtl, mtllib, l, p: not needed for shading with per-vertex colour.
  }
  if (corners.empty()) throw std::runtime_error(name + ": empty mesh (no triangles)");

  Mesh m;
  // One output vertex per distinct (position, normal) pair; without normals on every corner
  // the normals are computed smooth over the shared positions instead.
  std::map<std::pair<long long, long long>, uint32_t> ids;
  for (auto c : corners) {
    if (!all_normals) c.second = -1;
    auto [it, inserted] = ids.try_emplace(c, (uint32_t)m.vertexCount());
    if (inserted) {
      m.positions.insert(m.positions.end(), &pos[3 * c.first], &pos[3 * c.first] + 3);
      m.colors.insert(m.colors.end(), &col[3 * c.first], &col[3 * c.first] + 3);
      if (all_normals) m.normals.insert(m.normals.end(), &nrm[3 * c.second], &nrm[3 * c.second] + 3);
    }
    m.indices.push_back(it->second);
  }
  if (!all_normals) computeSmoothNormals(m);
  validateMesh(m, name);
  return m;
}

}  // namespace tessera::renderer
