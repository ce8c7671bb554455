// PLY reader (ascii and binary_little_endian): vertex x y z, optional nx ny nz and red green
// blue (uchar /255 or float), face vertex_indices lists fan-triangulated; other elements skipped.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

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

size_t typeSize(Type t) {
  static constexpr size_t kSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSize[(int)t];
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
    const size_t n = typeSize(t);
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

// The header: format, then elements with their properties; `body` is where the data starts.
struct Header {
  bool ascii = false;
  std::vector<Element> elements;
  size_t body = 0;
};

// Reads the header line by line; errors name the file and the header line.
class HeaderParser {
 public:
  HeaderParser(const std::string& bytes, const std::string& name) : bytes_(bytes), name_(name) {}
  Header parse();

 private:
  std::string nextLine();
  [[noreturn]] void bad(const std::string& msg) const {
    throw std::runtime_error(name_ + ": bad PLY header: line " + std::to_string(line_no_) + ": " + msg);
  }
  void format(std::istringstream& in);
  void element(std::istringstream& in);
  void property(std::istringstream& in, const std::string& line);
  void checkCounts() const;

  const std::string& bytes_;
  const std::string& name_;
  size_t pos_ = 0;
  int line_no_ = 0;
  bool have_format_ = false;
  Header h_;
};

Header HeaderParser::parse() {
  if (nextLine() != "ply") bad("expected 'ply'");
  for (;;) {
    const std::string line = nextLine();
    std::istringstream in(line);
    std::string kw;
    in >> kw;
    if (kw == "end_header") break;
    if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") format(in);
    else if (kw == "element") element(in);
    else if (kw == "property") property(in, line);
    else bad("unknown keyword '" + kw + "'");
  }
  if (!have_format_) bad("missing format line");
  h_.body = pos_;
  checkCounts();
  return h_;
}

std::string HeaderParser::nextLine() {
  if (pos_ >= bytes_.size()) throw std::runtime_error(name_ + ": bad PLY header: missing end_header");
  size_t end = bytes_.find('\n', pos_);
  if (end == std::string::npos) end = bytes_.size();
  std::string line = bytes_.substr(pos_, end - pos_);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  pos_ = end + 1;
  ++line_no_;
  return line;
}

void HeaderParser::format(std::istringstream& in) {
  std::string fmt, ver;
  in >> fmt >> ver;
  if (fmt == "ascii") h_.ascii = true;
  else if (fmt != "binary_little_endian") bad("unsupported format '" + fmt + "' (ascii | binary_little_endian)");
  have_format_ = true;
}

void HeaderParser::element(std::istringstream& in) {
  Element e;
  long long count = -1;
  if (!(in >> e.name >> count) || count < 0) bad("expected 'element <name> <count>'");
  e.count = (size_t)count;
  h_.elements.push_back(e);
}

// Refuses counts the body cannot hold before anything is allocated or looped over: an item
// takes at least one byte per property in ascii (a digit; separators not counted) and its
// fixed-size values and list lengths in binary. An element without properties takes no bytes,
// whatever its count, and is skipped whole (MeshReader).
void HeaderParser::checkCounts() const {
  size_t left = bytes_.size() - h_.body;
  for (const Element& e : h_.elements) {
    size_t per_item = 0;
    for (const Prop& p : e.props) per_item += h_.ascii ? 1 : typeSize(p.list ? p.count_type : p.type);
    if (per_item == 0) continue;
    if (e.count > left / per_item)
      throw std::runtime_error(name_ + ": bad PLY header: element '" + e.name + "' declares " + std::to_string(e.count) +
                               " items, but the " + std::to_string(bytes_.size() - h_.body) +
                               " bytes after the header hold at most " + std::to_string(left / per_item));
    left -= e.count * per_item;
  }
}

void HeaderParser::property(std::istringstream& in, const std::string& line) {
  if (h_.elements.empty()) bad("property before any element");
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
  h_.elements.back().props.push_back(p);
}

// Where an element's properties land: x y z nx ny nz red green blue (property index or -1) for
// vertices, the vertex index list for faces.
struct Layout {
  bool is_vertex = false, is_face = false;
  int slot[9];
  int list_prop = -1;
  bool normals() const { return slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0; }
  bool colors() const { return slot[6] >= 0 && slot[7] >= 0 && slot[8] >= 0; }
};

// Throws the header errors that only show once the element's role is known.
Layout layoutOf(const Element& e, const std::string& name) {
  Layout l;
  l.is_vertex = e.name == "vertex";
  l.is_face = e.name == "face";
  const char* kNames[9] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
  for (int k = 0; k < 9; ++k) {
    l.slot[k] = -1;
    for (size_t i = 0; i < e.props.size(); ++i)
      if (e.props[i].name == kNames[k] && !e.props[i].list) l.slot[k] = (int)i;
  }
  if (l.is_vertex && (l.slot[0] < 0 || l.slot[1] < 0 || l.slot[2] < 0))
    throw std::runtime_error(name + ": bad PLY header: vertex element needs properties x, y and z");
  if (l.is_face)
    for (size_t i = 0; i < e.props.size(); ++i)
      if (e.props[i].list && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
        l.list_prop = (int)i;
  if (l.is_face && l.list_prop < 0)
    throw std::runtime_error(name + ": bad PLY header: face element needs a vertex_indices list");
  return l;
}

// Reads every element of the body in order: vertices and faces into the mesh, others dropped.
class MeshReader {
 public:
  MeshReader(const std::string& bytes, const Header& header, const std::string& name)
      : header_(header), name_(name), body_(bytes, header.body, header.ascii, name) {
    for (const Element& e : header.elements)
      if (e.name == "vertex") vertex_count_ = e.count;
  }
  Mesh build();

 private:
  void readElement(const Element& e);
  void readList(const Prop& p, bool indices);
  void addVertex(const Element& e, const Layout& l);

  const Header& header_;
  const std::string& name_;
  Body body_;
  size_t vertex_count_ = 0;
  bool have_normals_ = false, have_colors_ = false;
  std::vector<double> vals_;    // the current item's scalar properties
  std::vector<uint32_t> poly_;  // the current face's vertex indices
  RelativePositions relative_;
  Mesh m_;
};

Mesh MeshReader::build() {
  for (const Element& e : header_.elements) readElement(e);
  if (m_.vertexCount() == 0 || m_.indices.empty()) throw std::runtime_error(name_ + ": empty mesh (no triangles)");
  if (!have_normals_) computeSmoothNormals(m_);
  if (!have_colors_)
    for (size_t v = 0; v < m_.vertexCount(); ++v) m_.colors.insert(m_.colors.end(), kDefaultMeshColor, kDefaultMeshColor + 3);
  validateMesh(m_, name_);
  return std::move(m_);
}

void MeshReader::readElement(const Element& e) {
  const Layout l = layoutOf(e, name_);
  if (e.props.empty()) return;  // nothing to read, however many items it declares
  if (l.is_vertex) {
    have_normals_ = l.normals();
    have_colors_ = l.colors();
    m_.positions.reserve(3 * e.count);
  }
  vals_.assign(e.props.size(), 0.0);
  for (size_t item = 0; item < e.count; ++item) {
    body_.where = e.name + " " + std::to_string(item);
    for (size_t i = 0; i < e.props.size(); ++i) {
      if (e.props[i].list) readList(e.props[i], (int)i == l.list_prop);
      else vals_[i] = body_.next(e.props[i].type);
    }
    if (l.is_vertex) addVertex(e, l);
  }
}

// Lists other than a face's vertex indices are read and dropped; a face is fan-triangulated.
void MeshReader::readList(const Prop& p, bool indices) {
  const double n = body_.next(p.count_type);
  if (!(n >= 0 && n <= 1e6) || n != std::floor(n)) body_.fail("bad list length " + std::to_string(n));
  poly_.clear();
  for (int k = 0; k < (int)n; ++k) {
    const double v = body_.next(p.type);
    if (!indices) continue;
    if (!(v >= 0 && v < (double)vertex_count_) || v != std::floor(v))
      body_.fail("vertex index " + std::to_string((long long)v) + " out of range (" + std::to_string(vertex_count_) +
                 " vertices)");
    poly_.push_back((uint32_t)v);
  }
  if (!indices) return;
  if (poly_.size() < 3) body_.fail("a face needs at least 3 vertices, got " + std::to_string(poly_.size()));
  for (size_t k = 1; k + 1 < poly_.size(); ++k) m_.indices.insert(m_.indices.end(), {poly_[0], poly_[k], poly_[k + 1]});
}

void MeshReader::addVertex(const Element& e, const Layout& l) {
  double p[3];
  for (int k = 0; k < 3; ++k) {
    p[k] = vals_[l.slot[k]];
    if (!std::isfinite(p[k])) body_.fail("position is not finite");
    if (std::fabs(p[k]) > 3e38) body_.fail(fmt::format("position {:g} is beyond a float's range (3e38)", p[k]));
  }
  if (!relative_.add(m_.positions, p)) body_.fail("position lies beyond a float's range (3e38) of the first vertex");
  if (have_normals_)
    for (int k = 3; k < 6; ++k) m_.normals.push_back((float)vals_[l.slot[k]]);
  if (have_colors_)
    for (int k = 6; k < 9; ++k) {
      const bool bytes_colour = e.props[l.slot[k]].type == Type::U8;
      m_.colors.push_back((float)std::clamp(bytes_colour ? vals_[l.slot[k]] / 255.0 : vals_[l.slot[k]], 0.0, 1.0));
    }
}

}  // namespace

Mesh parsePly(const std::string& bytes, const std::string& name) {
  const Header header = HeaderParser(bytes, name).parse();
  return MeshReader(bytes, header, name).build();
}

}  // namespace tessera::renderer
