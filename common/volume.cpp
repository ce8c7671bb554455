// Raw volume loading (little-endian uint8/uint16/float32) and the built-in procedural volumes.
#include "common/volume.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

#include <unistd.h>

#include <fmt/format.h>

#include "common/parallel.h"

namespace tessera {

Vec3 Volume::halfExtent() const {
  const std::array<int, 3> n = wholeDims();
  double e[3];
  double m = 0;
  for (int i = 0; i < 3; ++i) {
    e[i] = n[i] * spacing[i];
    m = std::max(m, e[i]);
  }
  if (!(m > 0)) return {0, 0, 0};
  return {0.5 * e[0] / m, 0.5 * e[1] / m, 0.5 * e[2] / m};
}

namespace {
struct TypeInfo {
  VoxelType type;
  const char* name;
  size_t size;
};
constexpr TypeInfo kTypes[] = {{VoxelType::UInt8, "uint8", 1},   {VoxelType::UInt16, "uint16", 2},
                               {VoxelType::Float32, "float32", 4}, {VoxelType::Int8, "int8", 1},
                               {VoxelType::Int16, "int16", 2},   {VoxelType::Int32, "int32", 4},
                               {VoxelType::UInt32, "uint32", 4}, {VoxelType::Float64, "float64", 8}};
}  // namespace

size_t voxelTypeSize(VoxelType t) {
  for (const auto& i : kTypes)
    if (i.type == t) return i.size;
  return 1;
}

const char* voxelTypeName(VoxelType t) {
  for (const auto& i : kTypes)
    if (i.type == t) return i.name;
  return "?";
}

std::optional<VoxelType> voxelTypeFromName(const std::string& name) {
  for (const auto& i : kTypes)
    if (name == i.name) return i.type;
  return std::nullopt;
}

std::string spacingProblem(const std::array<double, 3>& sp) {
  double lo = INFINITY, hi = 0;
  for (double s : sp) {
    if (!std::isfinite(s) || !(s >= kMinSpacing && s <= kMaxSpacing))
      return fmt::format("spacing {:.7g} must be finite and in [1e-30, 1e30]", s);
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  // Beyond this the thinnest axis is far below one pixel and the volume renders as nothing.
  if (hi / lo > kMaxSpacingRatio)
    return fmt::format("spacing ratio largest/smallest is {:.6g}, must be <= 1e6", hi / lo);
  return "";
}

std::string notRegularFile(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  switch (st.type()) {
    case std::filesystem::file_type::regular: return "";
    case std::filesystem::file_type::not_found: return "file not found";
    case std::filesystem::file_type::directory: return "is a directory, not a regular file";
    case std::filesystem::file_type::fifo: return "is a FIFO (named pipe), not a regular file";
    case std::filesystem::file_type::socket: return "is a socket, not a regular file";
    case std::filesystem::file_type::block: return "is a block device, not a regular file";
    case std::filesystem::file_type::character: return "is a character device, not a regular file";
    default: return "cannot be examined" + (ec ? ": " + ec.message() : std::string());
  }
}

uint64_t volumeLoadBytes(const std::array<int, 3>& dims) {
  const uint64_t n = (uint64_t)std::max(dims[0], 0) * (uint64_t)std::max(dims[1], 0) * (uint64_t)std::max(dims[2], 0);
  return n * sizeof(float);  // <= 2^48 * 4: no overflow
}

uint64_t physicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size : UINT64_MAX;
}

std::string memoryProblem(const std::array<int, 3>& dims) {
  const uint64_t need = volumeLoadBytes(dims), have = physicalMemoryBytes();
  if (need <= have) return "";
  std::string m = "[";  // built by appending: GCC 12 warns falsely (-Wrestrict) on "lit" + string&&
  m += std::to_string(dims[0]) + ", " + std::to_string(dims[1]) + ", " + std::to_string(dims[2]);
  m += "] voxels need " + std::to_string(need) + " bytes (" + std::to_string(need >> 30);
  m += " GiB) to load, more than this machine's " + std::to_string(have) + " bytes of memory";
  return m;
}

namespace {

// Runs body(z0, z1) over slabs of z on up to four threads, at least 8 slices each.
template <class F>
void parallelZ(int nz, F body) {
  parallelRanges(nz, threadCount(0, std::min(4, std::max(1, nz / 8))),
                 [&](long long z0, long long z1) { body((int)z0, (int)z1); });
}

// Calls f(x, y, z, value) for every voxel of v (a window or the whole), with x, y, z
// the voxel's index in the whole volume, over slabs of z in parallel.
template <class F>
void forEachVoxel(Volume& v, F f) {
  parallelZ(v.dims[2], [&](int z0, int z1) {
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < v.dims[1]; ++y)
        for (int x = 0; x < v.dims[0]; ++x) f(x + v.origin[0], y + v.origin[1], z + v.origin[2], v.values[v.index(x, y, z)]);
  });
}

// Smooth bump: 1 inside |d| <= inner, cosine fall-off to exactly 0 at |d| >= outer.
double bump(double d, double inner, double outer) {
  d = std::abs(d);
  if (d <= inner) return 1.0;
  if (d >= outer) return 0.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * (d - inner) / (outer - inner)));
}

void hollowShell(Volume& v) {
  const int n = v.wholeDims()[0];
  // Coordinates in [-1, 1] across the box; shell radius 0.75, total thickness 0.1 (5% of the edge).
  forEachVoxel(v, [&](int x, int y, int z, float& value) {
    double u = 2.0 * (x + 0.5) / n - 1, w = 2.0 * (y + 0.5) / n - 1, t = 2.0 * (z + 0.5) / n - 1;
    double r = std::sqrt(u * u + w * w + t * t);
    // Shell peaks at 0.5 and the core at 1.0, so a transfer function can tell them apart.
    double s = 0.5 * bump(r - 0.75, 0.02, 0.05) + bump(r, 0.10, 0.16);
    value = (float)std::min(1.0, s);
  });
}

void marschnerLobb(Volume& v) {
  const int n = v.wholeDims()[0];
  constexpr double kFm = 6.0, kAlpha = 0.25, kPi = std::numbers::pi;
  forEachVoxel(v, [&](int x, int y, int z, float& value) {
    double u = 2.0 * (x + 0.5) / n - 1, w = 2.0 * (y + 0.5) / n - 1, t = 2.0 * (z + 0.5) / n - 1;
    double rho = std::cos(2 * kPi * kFm * std::cos(kPi * std::sqrt(u * u + w * w) / 2));
    double s = (1 - std::sin(kPi * t / 2) + kAlpha * (1 + rho)) / (2 * (1 + kAlpha));
    value = (float)std::clamp(s, 0.0, 1.0);
  });
}

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// One octave of value noise: random values on a (c+1)^3 lattice, smoothstep-interpolated.
struct Lattice {
  int c;
  std::vector<float> val;
  Lattice(int cells, uint64_t seed) : c(cells), val((size_t)(cells + 1) * (cells + 1) * (cells + 1)) {
    for (size_t i = 0; i < val.size(); ++i) val[i] = (float)((splitmix64(seed * 0x100000001b3ull + i) >> 40) * 0x1p-24);
  }
  float at(int i, int j, int k) const { return val[i + (size_t)(c + 1) * (j + (size_t)(c + 1) * k)]; }
};

// Trilinear-smoothstep value of lattice L at p (coordinates in [0, 1]).
double latticeAt(const Lattice& L, const double p[3]) {
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    double q = p[a] * L.c;
    i[a] = std::min((int)q, L.c - 1);
    double t = q - i[a];
    f[a] = t * t * (3 - 2 * t);
  }
  auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  double c00 = lerp(L.at(i[0], i[1], i[2]), L.at(i[0] + 1, i[1], i[2]), f[0]);
  double c10 = lerp(L.at(i[0], i[1] + 1, i[2]), L.at(i[0] + 1, i[1] + 1, i[2]), f[0]);
  double c01 = lerp(L.at(i[0], i[1], i[2] + 1), L.at(i[0] + 1, i[1], i[2] + 1), f[0]);
  double c11 = lerp(L.at(i[0], i[1] + 1, i[2] + 1), L.at(i[0] + 1, i[1] + 1, i[2] + 1), f[0]);
  return lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
}

void noiseCloud(Volume& v, uint32_t seed) {
  const int n = v.wholeDims()[0];
  constexpr int kOctaves = 4;
  std::vector<Lattice> oct;
  for (int o = 0; o < kOctaves; ++o) oct.emplace_back(4 << o, splitmix64(seed) + (uint64_t)o * 7919);
  forEachVoxel(v, [&](int x, int y, int z, float& value) {
    double p[3] = {(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n};
    double sum = 0, amp = 0.5;
    for (const Lattice& L : oct) {
      sum += amp * latticeAt(L, p);
      amp *= 0.5;
    }
    // Fade towards the box faces so the cloud floats in empty space; threshold gives exact zeros.
    double u = 2 * p[0] - 1, w = 2 * p[1] - 1, t = 2 * p[2] - 1;
    double env = bump(std::sqrt(u * u + w * w + t * t), 0.45, 1.0);
    double s = (sum / 0.9375) * env;  // fBm of 4 octaves spans [0, 0.9375]
    value = (float)std::clamp((s - 0.33) / 0.4, 0.0, 1.0);
  });
}

// A head-like phantom: opaque, scan-like data whose rays end in a thin layer. Air (0)
// outside, soft tissue (0.3) under the skin, a thin skull (0.9) whose thickness ripples, a
// textured brain (about 0.42) with two ventricles (0.15); all well inside the box, as a
// scan's head is, so the box's faces never cut the data.
void headPhantom(Volume& v, uint32_t seed) {
  const int n = v.wholeDims()[0];
  const Lattice tex(24, splitmix64(seed)), bumps(6, splitmix64(seed + 1));
  forEachVoxel(v, [&](int x, int y, int z, float& value) {
    const double p[3] = {(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n};
    const double u = 2 * p[0] - 1, w = 2 * p[1] - 1, t = 2 * p[2] - 1;
    auto radius = [](double a, double b, double c, double ra, double rb, double rc) {
      return std::sqrt(a * a / (ra * ra) + b * b / (rb * rb) + c * c / (rc * rc));
    };
    const double r = radius(u, w, t, 0.72, 0.86, 0.80);  // 1 on the skin
    double s = 0.3 * bump(r, 0.97, 1.0);
    const double ripple = 0.04 * (latticeAt(bumps, p) - 0.5);
    s = std::max(s, 0.9 * bump(r - 0.88 - ripple, 0.025, 0.045));
    const double brain = bump(r, 0.80, 0.845);
    s = s * (1 - brain) + brain * (0.42 + 0.16 * (latticeAt(tex, p) - 0.5));
    for (double side : {-1.0, 1.0}) {
      const double vent = bump(radius(u - side * 0.11, w - 0.08, t, 0.06, 0.22, 0.09), 0.7, 1.0);
      s = s * (1 - vent) + 0.15 * vent;
    }
    value = (float)std::clamp(s, 0.0, 1.0);
  });
}

// Time-varying: seven soft blobs on tilted circles about the centre, each at a whole number
// of turns per period and breathing in size, so time 0..1 is one period and a loop closes.
// Values fall to exactly 0 outside each blob (empty space stays empty).
void movingBlobs(Volume& v, double time, uint32_t seed) {
  constexpr int kBlobs = 7;
  constexpr double kTwoPi = 2 * std::numbers::pi;
  struct Blob {
    double orbit, tilt, phase, size, turns, breaths;
  };
  Blob b[kBlobs];
  for (int i = 0; i < kBlobs; ++i) {
    const uint64_t h = splitmix64(seed * 977ull + (uint64_t)i);
    auto unit = [&](int k) { return (double)((h >> (8 * k)) & 0xff) / 255.0; };
    b[i] = {0.3 + 0.4 * unit(1), std::numbers::pi * unit(2), kTwoPi * unit(3), 0.2 + 0.12 * unit(4),
            (double)(1 + i % 3), (double)(1 + (i + 1) % 2)};
  }
  Vec3 centre[kBlobs];
  double size[kBlobs];
  for (int i = 0; i < kBlobs; ++i) {
    const double a = kTwoPi * b[i].turns * time + b[i].phase;
    const double x = b[i].orbit * std::cos(a), y = b[i].orbit * std::sin(a);
    centre[i] = {x, y * std::cos(b[i].tilt), y * std::sin(b[i].tilt)};
    size[i] = b[i].size * (1 + 0.35 * std::sin(kTwoPi * b[i].breaths * time + b[i].phase));
  }
  const int n = v.wholeDims()[0];
  forEachVoxel(v, [&](int x, int y, int z, float& value) {
    const Vec3 p{2.0 * (x + 0.5) / n - 1, 2.0 * (y + 0.5) / n - 1, 2.0 * (z + 0.5) / n - 1};
    double s = 0;
    for (int i = 0; i < kBlobs; ++i) s += (0.6 + 0.06 * i) * bump(length(p - centre[i]) / size[i], 0.3, 1.0);
    value = (float)std::min(1.0, s);
  });
}

constexpr const char* kGenerators[] = {"hollow-shell", "marschner-lobb", "noise-cloud", "head", "moving-blobs"};

}  // namespace

const std::string& generatorNames() {
  static const std::string names = [] {
    std::string s;
    for (const char* g : kGenerators) s += (s.empty() ? "" : " | ") + std::string(g);
    return s;
  }();
  return names;
}

bool isTimeGenerator(const std::string& name) { return name == "moving-blobs"; }

bool isGeneratorName(const std::string& name) {
  return std::find(std::begin(kGenerators), std::end(kGenerators), name) != std::end(kGenerators);
}

Volume generateVolume(const GeneratorSpec& spec) {
  return generateVolume(spec, VoxelBox{{0, 0, 0}, {spec.size, spec.size, spec.size}});
}

Volume generateVolume(const GeneratorSpec& spec, const VoxelBox& box) {
  if (spec.size < 2) throw std::invalid_argument("generator '" + spec.name + "': size must be >= 2, got " + std::to_string(spec.size));
  if (spec.size > 2048) throw std::invalid_argument("generator '" + spec.name + "': size must be <= 2048, got " + std::to_string(spec.size));
  if (std::string p = spacingProblem(spec.spacing); !p.empty()) throw std::invalid_argument("generator: " + p);
  const std::array<int, 3> whole{spec.size, spec.size, spec.size};
  if (std::string p = windowProblem(whole, box); !p.empty()) throw std::invalid_argument("generator: " + p);
  Volume v;
  for (int a = 0; a < 3; ++a) v.dims[a] = box.hi[a] - box.lo[a];
  if (std::string p = memoryProblem(v.dims); !p.empty()) throw std::invalid_argument("generator: " + p);
  v.origin = box.lo;
  v.whole_dims = whole;
  v.spacing = spec.spacing;
  v.values.assign(v.voxelCount(), 0.0f);
  if (spec.name == "hollow-shell") hollowShell(v);
  else if (spec.name == "marschner-lobb") marschnerLobb(v);
  else if (spec.name == "noise-cloud") noiseCloud(v, spec.seed);
  else if (spec.name == "head") headPhantom(v, spec.seed);
  else if (spec.name == "moving-blobs") movingBlobs(v, spec.time, spec.seed);
  else throw std::invalid_argument("unknown generator '" + spec.name + "' (" + generatorNames() + ")");
  const auto [mn, mx] = std::minmax_element(v.values.begin(), v.values.end());
  v.data_range = {*mn, *mx};  // of the window: a generator's values are normalised already
  v.mapped_range = {0, 1};
  return v;
}

std::string windowProblem(const std::array<int, 3>& whole, const VoxelBox& box) {
  for (int a = 0; a < 3; ++a)
    if (box.lo[a] < 0 || box.hi[a] > whole[a] || box.lo[a] >= box.hi[a])
      return "window [" + std::to_string(box.lo[0]) + ", " + std::to_string(box.lo[1]) + ", " +
             std::to_string(box.lo[2]) + "] .. [" + std::to_string(box.hi[0]) + ", " + std::to_string(box.hi[1]) +
             ", " + std::to_string(box.hi[2]) + ") is empty or outside the volume's " + std::to_string(whole[0]) +
             " x " + std::to_string(whole[1]) + " x " + std::to_string(whole[2]) + " voxels";
  return "";
}

std::string rangeProblem(const Volume& v) {
  const auto [lo, hi] = v.mapped_range;
  const auto [mn, mx] = v.data_range;
  if (lo <= mx && hi >= mn && !(mn == mx && lo == mn)) return "";
  auto num = [](double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return std::string(b);
  };
  const std::string data = "the data's values run " + num(mn) + " .. " + num(mx);
  if (mn == mx) return "every voxel has the value " + num(mn) + ": the image shows one constant colour or nothing";
  return "range [" + num(lo) + ", " + num(hi) + "] lies " + (lo > mx ? "above" : "below") + " every value (" + data +
         "): every voxel maps to the transfer function's " + (lo > mx ? "first" : "last") +
         " point, so the image is likely empty or uniform; leave range out to span the data";
}

}  // namespace tessera
