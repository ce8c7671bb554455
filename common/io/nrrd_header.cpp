// NRRD headers (teem's format, http://teem.sourceforge.net/nrrd/format.html; see
// volume_files.h): the fields a scalar 3-D volume needs, checked against teem's own files
// in the tests. The data follows the header's blank line (.nrrd) or sits in "data file"
// (.nhdr), raw or gzip-encoded.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/io/volume_files.h"

namespace tessera {
namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::optional<VoxelType> nrrdType(const std::string& t) {
  static const std::map<std::string, VoxelType> kNames = {
      {"uchar", VoxelType::UInt8},          {"unsigned char", VoxelType::UInt8},   {"uint8", VoxelType::UInt8},
      {"uint8_t", VoxelType::UInt8},        {"signed char", VoxelType::Int8},      {"int8", VoxelType::Int8},
      {"int8_t", VoxelType::Int8},          {"short", VoxelType::Int16},           {"short int", VoxelType::Int16},
      {"signed short", VoxelType::Int16},   {"signed short int", VoxelType::Int16}, {"int16", VoxelType::Int16},
      {"int16_t", VoxelType::Int16},        {"ushort", VoxelType::UInt16},         {"unsigned short", VoxelType::UInt16},
      {"unsigned short int", VoxelType::UInt16}, {"uint16", VoxelType::UInt16},    {"uint16_t", VoxelType::UInt16},
      {"int", VoxelType::Int32},            {"signed int", VoxelType::Int32},      {"int32", VoxelType::Int32},
      {"int32_t", VoxelType::Int32},        {"uint", VoxelType::UInt32},           {"unsigned int", VoxelType::UInt32},
      {"uint32", VoxelType::UInt32},        {"uint32_t", VoxelType::UInt32},       {"float", VoxelType::Float32},
      {"double", VoxelType::Float64}};
  const auto it = kNames.find(t);
  return it == kNames.end() ? std::nullopt : std::optional<VoxelType>(it->second);
}

std::string lower(std::string v) {
  std::transform(v.begin(), v.end(), v.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  return v;
}

// A spacing NRRD leaves unknown (nan, none, 0, or no field) is 1 and marked unknown (a
// warning says so), as NIfTI's 0; the scene may replace it.
bool isKnown(double x) { return std::isfinite(x) && x != 0; }

// "spacings: a b c", or "space directions: (x,y,z) (x,y,z) (x,y,z)" whose lengths are the
// spacing (the rotation is not applied; a vector has "space dimension" components, and an
// axis that is not space is "none"); neither: 1. False if present but unreadable.
bool readSpacing(std::map<std::string, std::string>& f, std::array<double, 3>& spacing, std::array<bool, 3>& known) {
  auto set = [&](int a, double v) {
    known[a] = isKnown(v);
    spacing[a] = known[a] ? std::fabs(v) : 1.0;
  };
  known = {false, false, false};
  if (f.count("spacings")) {
    std::istringstream sp(f["spacings"]);
    for (int a = 0; a < 3; ++a) {
      std::string t;
      if (!(sp >> t)) return false;
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);  // reads nan too
      if (end != t.c_str() + t.size()) return false;
      set(a, v);
    }
  } else if (f.count("spacedirections")) {
    const std::string& d = f["spacedirections"];
    size_t i = 0;
    for (int a = 0; a < 3; ++a) {
      i = d.find_first_not_of(" \t", i);
      if (i == std::string::npos) return false;
      if (lower(d.substr(i, 4)) == "none") {
        set(a, 0), i += 4;
        continue;
      }
      const size_t close = d.find(')', i);
      if (d[i] != '(' || close == std::string::npos) return false;
      std::string inner = d.substr(i + 1, close - i - 1);
      std::replace(inner.begin(), inner.end(), ',', ' ');
      std::istringstream v(inner);
      double c = 0, sum = 0;
      int n = 0;
      while (v >> c) sum += c * c, ++n;
      if (n == 0 || !v.eof()) return false;
      set(a, std::sqrt(sum));
      i = close + 1;
    }
  }
  return true;
}

// Teem's spellings of a field name: "byte skip" is also "byteskip", and any case.
std::string fieldKey(const std::string& name) {
  std::string k = lower(name);
  k.erase(std::remove(k.begin(), k.end(), ' '), k.end());
  return k;
}

}  // namespace

RawVolumeSpec readNrrdHeader(const std::string& path, int* time_steps) {
  auto fail = [&](const std::string& what) -> RawVolumeSpec { throw std::runtime_error(path + ": " + what); };
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("cannot open NRRD file");
  std::string line;
  if (!std::getline(in, line) || line.rfind("NRRD000", 0) != 0) fail("not a NRRD file (no NRRD000x magic on line 1)");
  std::map<std::string, std::string> f;
  bool blank_line = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {  // the end of the header; attached data follows
      blank_line = true;
      break;
    }
    if (line[0] == '#') continue;
    const size_t colon = line.find(": "), pair = line.find(":=");
    if (pair != std::string::npos && (colon == std::string::npos || pair < colon)) continue;  // key:=value
    if (colon == std::string::npos) fail("header line '" + line + "' is not 'field: value'");
    const std::string key = fieldKey(line.substr(0, colon));
    if (f.count(key)) fail("field '" + line.substr(0, colon) + "' appears twice");
    f[key] = trim(line.substr(colon + 2));
  }
  RawVolumeSpec s;
  s.format = VolumeFormat::Nrrd;
  s.file = path;
  auto need = [&](const char* key) -> const std::string& {
    if (!f.count(key)) fail(std::string("the header has no '") + key + "' field");
    return f[key];
  };
  if (auto t = nrrdType(lower(need("type")))) s.type = *t;
  else fail("type '" + f["type"] + "' is not a scalar type Tessera renders");
  const std::string dimension = need("dimension");
  if (dimension != "3" && !(dimension == "4" && time_steps))
    fail("dimension " + dimension + ": Tessera renders 3-D volumes (dimension: 3" +
         (time_steps ? ", or 4 with time as the last axis)" : ")"));
  const int axes = dimension == "4" ? 4 : 3;
  std::istringstream sizes(need("sizes"));
  long long steps = 1;
  for (int a = 0; a < axes; ++a) {
    long long n = 0;
    if (!(sizes >> n) || n < 1 || n > (a < 3 ? 65536 : 1000000))
      fail("sizes '" + f["sizes"] + "': expected " + dimension + " sizes, in 1..65536" + (a < 3 ? "" : " (time: 1..1000000)"));
    if (a < 3) s.dims[a] = (int)n;
    else steps = n;
  }
  if (std::string more; sizes >> more) fail("sizes '" + f["sizes"] + "': expected " + dimension + " sizes");
  if (time_steps) *time_steps = (int)steps;
  if (f.count("kinds")) {  // RGB, vector or tensor axes hold a voxel's components, not space
    std::istringstream kinds(f["kinds"]);
    std::string k;
    for (int a = 0; a < axes && kinds >> k; ++a) {
      const std::string kl = lower(k);
      const bool unknown = kl == "???" || kl == "none";  // NRRD's "says nothing"
      // A 4-D file's last axis is its steps: time (or unnamed); vector, list or colour
      // components are not time steps.
      if (kl == "domain" || kl == "space" || unknown || ((axes == 3 || a == 3) && kl == "time")) continue;
      fail("kinds '" + f["kinds"] + "': axis " + std::to_string(a) + " is '" + k + "'; " +
           (axes == 4 ? "a 4-D volume needs 3 space axes then time" : "a volume's 3 axes must be space (domain)"));
    }
  }
  if (!readSpacing(f, s.spacing, s.spacing_known)) fail("spacing '" + f["spacings"] + f["spacedirections"] + "'");
  // Its range is checked by the scene parser, after the scene's volume.spacing (which may replace it).
  const std::string enc = lower(need("encoding"));
  if (enc == "gzip" || enc == "gz") s.gzip = true;
  else if (enc != "raw") fail("encoding '" + enc + "': Tessera reads raw and gzip");
  if (voxelTypeSize(s.type) > 1) {
    const std::string endian = lower(need("endian"));
    if (endian != "little" && endian != "big") fail("endian '" + endian + "': expected little or big");
    s.big_endian = endian == "big";
  }
  if (f.count("lineskip") && f["lineskip"] != "0") fail("line skip " + f["lineskip"] + " is not supported");
  const std::string data = f.count("datafile") ? f["datafile"] : "";
  // Several data files: "LIST", or a printf pattern with its numbers; any other name is one
  // file, spaces and all.
  if (data.rfind("LIST", 0) == 0 || (data.find('%') != std::string::npos && data.find(' ') != std::string::npos))
    fail("data file '" + data + "': one file expected");
  if (data.empty()) {
    // Attached: right after the blank line (where a gzip stream starts, if encoded).
    const std::streamoff at = blank_line ? (std::streamoff)in.tellg() : -1;
    if (at < 0) fail("the header has no 'data file' field and no blank line after it, so it holds no data");
    (s.gzip ? s.gzip_start : s.offset) = (uint64_t)at;
  } else {
    const std::filesystem::path p(data);
    s.data_file = (p.is_relative() ? std::filesystem::path(path).parent_path() / p : p).lexically_normal().string();
  }
  long long skip = 0;
  if (f.count("byteskip")) {
    const std::string& v = f["byteskip"];
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), skip);
    if (ec != std::errc() || end != v.data() + v.size() || v.empty())
      fail("byte skip '" + v + "' is not an integer (bytes to skip, or -1: the data ends the file)");
  }
  if (skip == -1 && !s.gzip) {  // the data is the file's last bytes
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(s.samples(), ec);
    const uintmax_t bytes = (uintmax_t)s.dims[0] * s.dims[1] * s.dims[2] * voxelTypeSize(s.type) * steps;
    if (ec) fail("byte skip -1: cannot read the size of the data file " + s.samples() + ": " + ec.message());
    if (size < bytes)
      fail("byte skip -1 but the data file " + s.samples() + " has " + std::to_string(size) + " bytes, fewer than the " +
           std::to_string(bytes) + " of its samples");
    s.offset = size - bytes;
  } else if (skip < 0) {
    fail("byte skip " + f["byteskip"] + " is not supported with encoding " + enc);
  } else {
    s.offset += (uint64_t)skip;  // with gzip, bytes of the decompressed stream (as teem skips them)
  }
  return s;
}

}  // namespace tessera
