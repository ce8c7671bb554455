// NRRD headers (teem's format, http://teem.sourceforge.net/nrrd/format.html; see
// volume_files.h): the fields a scalar 3-D volume needs, checked against teem's own files
// in the tests. The data follows the header's blank line (.nrrd) or sits in "data file"
// (.nhdr), raw or gzip-encoded.
#include <algorithm>
#include <charconv>
#include <cmath>
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

// "spacings: a b c", or "space directions: (x,y,z) (x,y,z) (x,y,z)" whose lengths are the
// spacing (the rotation is not applied); neither: 1. False if present but unreadable.
bool readSpacing(std::map<std::string, std::string>& f, std::array<double, 3>& spacing) {
  if (f.count("spacings")) {
    std::istringstream sp(f["spacings"]);
    for (double& x : spacing)
      if (!(sp >> x) || !(std::fabs(x) > 0)) return false;
    for (double& x : spacing) x = std::fabs(x);
  } else if (f.count("space directions")) {
    std::string d = f["space directions"];
    std::replace_if(d.begin(), d.end(), [](char c) { return c == '(' || c == ')' || c == ','; }, ' ');
    std::istringstream sd(d);
    for (double& x : spacing) {
      double v[3];
      if (!(sd >> v[0] >> v[1] >> v[2])) return false;
      x = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    }
  }
  return true;
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
    if (line[0] == '#' || line.find(":=") != std::string::npos) continue;  // comments, key/value pairs
    const size_t colon = line.find(": ");
    if (colon == std::string::npos) fail("header line '" + line + "' is not 'field: value'");
    std::string key = line.substr(0, colon);
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return (char)std::tolower(c); });
    f[key] = trim(line.substr(colon + 2));
  }
  RawVolumeSpec s;
  s.format = VolumeFormat::Nrrd;
  s.file = path;
  auto need = [&](const char* key) -> const std::string& {
    if (!f.count(key)) fail(std::string("the header has no '") + key + "' field");
    return f[key];
  };
  if (auto t = nrrdType(need("type"))) s.type = *t;
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
  if (time_steps) *time_steps = (int)steps;
  if (f.count("kinds")) {  // RGB, vector or tensor axes hold a voxel's components, not space
    std::istringstream kinds(f["kinds"]);
    std::string k;
    for (int a = 0; a < 3 && kinds >> k; ++a) {
      const bool unknown = k == "???" || k == "none";  // NRRD's "says nothing"
      if (k == "domain" || k == "space" || unknown || (axes == 3 && k == "time")) continue;
      fail("kinds '" + f["kinds"] + "': axis " + std::to_string(a) + " is '" + k + "'; " +
           (axes == 4 ? "a 4-D volume needs 3 space axes then time" : "a volume's 3 axes must be space (domain)"));
    }
  }
  if (!readSpacing(f, s.spacing)) fail("spacing '" + f["spacings"] + f["space directions"] + "'");
  // Its range is checked by the scene parser, after the scene's volume.spacing (which may replace it).
  const std::string enc = need("encoding");
  if (enc == "gzip" || enc == "gz") s.gzip = true;
  else if (enc != "raw") fail("encoding '" + enc + "': Tessera reads raw and gzip");
  if (voxelTypeSize(s.type) > 1) {
    const std::string endian = need("endian");
    if (endian != "little" && endian != "big") fail("endian '" + endian + "': expected little or big");
    s.big_endian = endian == "big";
  }
  if (f.count("line skip") && f["line skip"] != "0") fail("line skip " + f["line skip"] + " is not supported");
  const std::string data = f.count("data file") ? f["data file"] : f.count("datafile") ? f["datafile"] : "";
  if (data.find(' ') != std::string::npos || data == "LIST") fail("data file '" + data + "': one file expected");
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
  if (f.count("byte skip")) {
    const std::string& v = f["byte skip"];
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), skip);
    if (ec != std::errc() || end != v.data() + v.size() || v.empty())
      fail("byte skip '" + v + "' is not an integer (bytes to skip, or -1: the data ends the file)");
  }
  if (skip == -1 && !s.gzip) {  // the data is the file's last bytes
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(s.samples(), ec);
    const uintmax_t bytes = (uintmax_t)s.dims[0] * s.dims[1] * s.dims[2] * voxelTypeSize(s.type) * steps;
    if (ec || size < bytes) fail("byte skip -1 but the data file is shorter than the data");
    s.offset = size - bytes;
  } else if (skip < 0) {
    fail("byte skip " + f["byte skip"] + " is not supported with encoding " + enc);
  } else if (s.gzip) {
    if (skip) fail("byte skip with gzip encoding is not supported");
  } else {
    s.offset += (uint64_t)skip;
  }
  return s;
}

}  // namespace tessera
