// Wavefront OBJ reader: v (optionally with r g b), vn, f with v, v/vt, v/vt/vn and v//vn
// corners and negative (relative) indices; polygons fan-triangulated; other statements ignored.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

namespace {

// Resolves a 1-based (or negative, relative) OBJ index against `count` items; -1 if out of range.
long long resolve(long long idx, size_t count) {
  if (idx > 0 && (size_t)idx <= count) return idx - 1;
  if (idx < 0 && (size_t)(-idx) <= count) return (long long)count + idx;
  return -1;
}

// A face corner as (position, normal); the normal is -1 when the corner has none.
using Corner = std::pair<long long, long long>;

// Reads the statements line by line into flat arrays; build() then welds them into a Mesh.
// Errors name the file and the line.
class ObjParser {
 public:
  explicit ObjParser(const std::string& name) : name_(name) {}
  void parse(const std::string& text);
  Mesh build() const;

 private:
  [[noreturn]] void fail(const std::string& msg) const {
    throw std::runtime_error(name_ + ": line " + std::to_string(line_no_) + ": " + msg);
  }
  std::vector<double> numbers(std::istringstream& ls, int min, int max) const;
  void vertex(std::istringstream& ls);
  void normal(std::istringstream& ls);
  void face(std::istringstream& ls);
  Corner corner(const std::string& tok);

  const std::string& name_;
  int line_no_ = 0;
  std::vector<float> pos_, col_, nrm_;
  RelativePositions relative_;
  std::vector<Corner> corners_;  // three per triangle
  bool all_normals_ = true;
};

void ObjParser::parse(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  for (std::string part; std::getline(in, part);) {
    ++line_no_;
    if (!part.empty() && part.back() == '\r') part.pop_back();
    // A trailing backslash continues a statement on the next line; '#' starts a comment,
    // also after a statement ("v 0 0 0 # origin"); both refused before (found by review).
    if (!part.empty() && part.back() == '\\') {
      line += part.substr(0, part.size() - 1) + " ";
      continue;
    }
    line += part;
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream ls(std::exchange(line, {}));
    std::string kw;
    if (!(ls >> kw)) continue;
    if (kw == "v") vertex(ls);
    else if (kw == "vn") normal(ls);
    else if (kw == "f") face(ls);
    // vt, o, g, s, usemtl, mtllib, l, p: not needed for shading with per-vertex colour.
  }
}

std::vector<double> ObjParser::numbers(std::istringstream& ls, int min, int max) const {
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
}

void ObjParser::vertex(std::istringstream& ls) {
  const auto v = numbers(ls, 3, 7);  // x y z [w] or x y z r g b
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(v[k]) || std::fabs(v[k]) > 3e38)
      fail(std::isfinite(v[k]) ? fmt::format("vertex position {:g} is beyond a float's range (3e38)", v[k])
                               : "vertex position is not finite");
  if (!relative_.add(pos_, v.data())) fail("vertex position lies beyond a float's range (3e38) of the first vertex");
  const bool has_rgb = v.size() >= 6;
  for (int k = 0; k < 3; ++k) col_.push_back(has_rgb ? (float)std::clamp(v[3 + k], 0.0, 1.0) : kDefaultMeshColor[k]);
}

void ObjParser::normal(std::istringstream& ls) {
  const auto v = numbers(ls, 3, 3);
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(v[k])) fail("normal is not finite");
    nrm_.push_back((float)v[k]);
  }
}

void ObjParser::face(std::istringstream& ls) {
  std::vector<Corner> poly;
  std::string tok;
  while (ls >> tok) poly.push_back(corner(tok));
  if (poly.size() < 3) fail("a face needs at least 3 vertices, got " + std::to_string(poly.size()));
  for (size_t k = 1; k + 1 < poly.size(); ++k) corners_.insert(corners_.end(), {poly[0], poly[k], poly[k + 1]});
}

// One of v, v/vt, v/vt/vn, v//vn; the texture index is ignored.
Corner ObjParser::corner(const std::string& tok) {
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
  const long long v = resolve(vi, pos_.size() / 3);
  if (v < 0)
    fail("vertex index " + std::to_string(vi) + " out of range (" + std::to_string(pos_.size() / 3) +
         " vertices so far)");
  long long n = -1;
  if (ni != 0) {
    n = resolve(ni, nrm_.size() / 3);
    if (n < 0)
      fail("normal index " + std::to_string(ni) + " out of range (" + std::to_string(nrm_.size() / 3) +
           " normals so far)");
  }
  all_normals_ = all_normals_ && n >= 0;
  return {v, n};
}

Mesh ObjParser::build() const {
  if (corners_.empty()) throw std::runtime_error(name_ + ": empty mesh (no triangles)");
  Mesh m;
  // One output vertex per distinct (position, normal) pair; without normals on every corner
  // the normals are computed smooth over the shared positions instead.
  std::map<Corner, uint32_t> ids;
  for (Corner c : corners_) {
    if (!all_normals_) c.second = -1;
    auto [it, inserted] = ids.try_emplace(c, (uint32_t)m.vertexCount());
    if (inserted) {
      m.positions.insert(m.positions.end(), &pos_[3 * c.first], &pos_[3 * c.first] + 3);
      m.colors.insert(m.colors.end(), &col_[3 * c.first], &col_[3 * c.first] + 3);
      if (all_normals_) m.normals.insert(m.normals.end(), &nrm_[3 * c.second], &nrm_[3 * c.second] + 3);
    }
    m.indices.push_back(it->second);
  }
  if (!all_normals_) computeSmoothNormals(m);
  validateMesh(m, name_);
  return m;
}

}  // namespace

Mesh parseObj(const std::string& text, const std::string& name) {
  ObjParser parser(name);
  parser.parse(text);
  return parser.build();
}

}  // namespace tessera::renderer
