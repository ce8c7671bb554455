// PLY reader (ascii and binary_little_endian): vertex x y z, optional nx ny nz and red green
// blue (uchar /255 or float), face vertex_indices lists fan-triangulated; other elements skipped.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

namespace {

enum class Type { I8, U8, I16, U16, I32, U32, F32, F64 };

bool parseType(const std::string& s, Type& t) {
  static const struct { const char* name; Type type; } kTypes[] = {
      {"char", Type::I8},    {"int8", Type::I8},     {"uchar", Type::U8},   {"uint8", Type::U8},
      {"short", Type::I16},  {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16},
      {"int", Type::I32},    {"int32", Type::I32},   {"uint", Type::U32},   {"uint32", Type::U32},
      {"float", Type::F32},  {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const auto& k : kTypes)
    if (s == k.name) {
      t = k.type;
      return true;
    }
  return false;
}

struct Prop {
  std::string name;
  Type type = Type::F32;
  bool list = false;
  Type count_type = Type::U8;
};
struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Prop> props;
};

// Reads values from the body, ascii tokens or little-endian binary; errors name the element.
class Body {
 public:
  Body(const std::string& bytes, size_t pos, bool ascii, const std::string& name)
      : b_(bytes), pos_(pos), ascii_(ascii), name_(name) {}
  std::string where;  // "vertex 12", set by the caller per element

  double next(Type t) {
    if (ascii_) return nextToken();
    static constexpr size_t kSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
    const size_t n = kSize[(int)t];
    if (pos_ + n > b_.size()) fail("unexpected end of file");
    unsigned char raw[8];
    std::memcpy(raw, b_.data() + pos_, n);
    pos_ += n;
    static_assert(std::endian::native == std::endian::little, "PLY binary reader assumes a little-endian host");
    switch (t) {
      case Type::I8: return (double)(int8_t)raw[0];
      case Type::U8: return (double)raw[0];
      case Type::I16: { int16_t v; std::memcpy(&v, raw, 2); return v; }
      case Type::U16: { uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case Type::I32: { int32_t v; std::memcpy(&v, raw, 4); return v; }
      case Type::U32: { uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case Type::F32: { float v; std::memcpy(&v, raw, 4); return v; }
      case Type::F64: { double v; std::memcpy(&v, raw, 8); return v; }
    }
    return 0;
  }
  [[noreturn]] void fail(const std::string& msg) const { throw std::runtime_error(name_ + ": " + where + ": " + msg); }

 private:
  double nextToken() {
    while (pos_ < b_.size() && std::isspace((unsigned char)b_[pos_])) ++pos_;
    if (pos_ >= b_.size()) fail("unexpected end of file");
    size_t end = pos_;
    while (end < b_.size() && !std::isspace((unsigned char)b_[end])) ++end;
    const std::string tok = b_.substr(pos_, end - pos_);
    pos_ = end;
    char* stop = nullptr;
    const double v = std::strtod(tok.c_str(), &stop);
    if (stop != tok.c_str() + tok.size()) fail("expected a number, got '" + tok + "'");
    return v;
  }
  const std::string& b_;
  size_t pos_;
  bool ascii_;
  const std::string& name_;
};

}  // namespace

Mesh parsePly(const std::string& bytes, const std::string& name) {
  size_t pos = 0;
  int line_no = 0;
  auto headerLine = [&]() {
    if (pos >= bytes.size()) throw std::runtime_error(name + ": bad PLY header: missing end_header");
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    std::string line = bytes.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = end + 1;
    ++line_no;
    return line;
  };
  auto bad = [&](const std::string& msg) {
    throw std::runtime_error(name + ": bad PLY header: line " + std::to_string(line_no) + ": " + msg);
  };
  if (headerLine() != "ply") bad("expected 'ply'");
  bool ascii = false, have_format = false;
  std::vector<Element> elements;
  for (;;) {
    const std::string line = headerLine();
    std::istringstream in(line);
    std::string kw;
    in >> kw;
    if (kw == "end_header") break;
    if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      std::string fmt, ver;
      in >> fmt >> ver;
      if (fmt == "ascii") ascii = true;
      else if (fmt != "binary_little_endian") bad("unsupported format '" + fmt + "' (ascii | binary_little_endian)");
      have_format = true;
    } else if (kw == "element") {
      Element e;
      long long count = -1;
      if (!(in >> e.name >> count) || count < 0) bad("expected 'element <name> <count>'");
      e.count = (size_t)count;
      elements.push_back(e);
    } else if (kw == "property") {
      if (elements.empty()) bad("property before any element");
      Prop p;
      std::string t;
      in >> t;
      if (t == "list") {
        std::string ct, it;
        in >> ct >> it >> p.name;
        p.list = true;
        if (!parseType(ct, p.count_type) || !parseType(it, p.type)) bad("unknown list type in '" + line + "'");
      } else {
        in >> p.name;
        if (!parseType(t, p.type)) bad("unknown property type '" + t + "'");
      }
      if (p.name.empty()) bad("property without a name");
      elements.back().props.push_back(p);
    } else {
      bad("unknown keyword '" + kw + "'");
    }
  }
  if (!have_format) bad("missing format line");

  Mesh m;
  bool have_normals = false, have_colors = false;
  size_t vertex_count = 0;
  for (const Element& e : elements)
    if (e.name == "vertex") vertex_count = e.count;
  Body body(bytes, pos, ascii, name);
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int slot[9];  // property index of x y z nx ny nz red green blue, or -1
    const char* kNames[9] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
    for (int k = 0; k < 9; ++k) {
      slot[k] = -1;
      for (size_t i = 0; i < e.props.size(); ++i)
        if (e.props[i].name == kNames[k] && !e.props[i].list) slot[k] = (int)i;
    }
    if (is_vertex) {
      if (slot[0] < 0 || slot[1] < 0 || slot[2] < 0)
        throw std::runtime_error(name + ": bad PLY header: vertex element needs properties x, y and z");
      have_normals = slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0;
      have_colors = slot[6] >= 0 && slot[7] >= 0 && slot[8] >= 0;
      m.positions.reserve(3 * e.count);
    }
    int list_prop = -1;
    if (is_face)
      for (size_t i = 0; i < e.props.size(); ++i)
        if (e.props[i].list && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
          list_prop = (int)i;
    if (is_face && list_prop < 0)
      throw std::runtime_error(name + ": bad PLY header: face element needs a vertex_indices list");
    std::vector<double> vals(e.props.size());
    std::vector<uint32_t> poly;
    for (size_t item = 0; item < e.count; ++item) {
      body.where = e.name + " " + std::to_string(item);
      for (size_t i = 0; i < e.props.size(); ++i) {
        const Prop& p = e.props[i];
        if (!p.list) {
          vals[i] = body.next(p.type);
          continue;
        }
        const double n = body.next(p.count_type);
        if (!(n >= 0 && n <= 1e6) || n != std::floor(n)) body.fail("bad list length " + std::to_string(n));
        poly.clear();
        for (int k = 0; k < (int)n; ++k) {
          const double v = body.next(p.type);
          if ((int)i != list_prop) continue;
          if (!(v >= 0 && v < (double)vertex_count) || v != std::floor(v))
            body.fail("vertex index " + std::to_string((long long)v) + " out of range (" +
                      std::to_string(vertex_count) + " vertices)");
          poly.push_back((uint32_t)v);
        }
        if ((int)i == list_prop) {
          if (poly.size() < 3) body.fail("a face needs at least 3 vertices, got " + std::to_string(poly.size()));
          for (size_t k = 1; k + 1 < poly.size(); ++k) m.indices.insert(m.indices.end(), {poly[0], poly[k], poly[k + 1]});
        }
      }
      if (!is_vertex) continue;
      for (int k = 0; k < 3; ++k) {
        const double v = vals[slot[k]];
        if (!std::isfinite(v) || std::fabs(v) > 3e38) body.fail("position is not finite");
        m.positions.push_back((float)v);
      }
      if (have_normals)
        for (int k = 3; k < 6; ++k) m.normals.push_back((float)vals[slot[k]]);
      if (have_colors)
        for (int k = 6; k < 9; ++k) {
          const bool bytes_colour = e.props[slot[k]].type == Type::U8;
          m.colors.push_back((float)std::clamp(bytes_colour ? vals[slot[k]] / 255.0 : vals[slot[k]], 0.0, 1.0));
        }
    }
  }
  if (m.vertexCount() == 0 || m.indices.empty()) throw std::runtime_error(name + ": empty mesh (no triangles)");
  if (!have_normals) computeSmoothNormals(m);
  if (!have_colors)
    for (size_t v = 0; v < m.vertexCount(); ++v) m.colors.insert(m.colors.end(), kDefaultMeshColor, kDefaultMeshColor + 3);
  validateMesh(m, name);
  return m;
}

}  // namespace tessera::renderer
