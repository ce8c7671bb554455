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

#include "common/parallel.h"

namespace tessera {

Vec3 Volume::halfExtent() const {
  double e[3];
  double m = 0;
  for (int i = 0; i < 3; ++i) {
    e[i] = dims[i] * spacing[i];
    m = std::max(m, e[i]);
  }
  if (!(m > 0)) return {0, 0, 0};
  return {0.5 * e[0] / m, 0.5 * e[1] / m, 0.5 * e[2] / m};
}

size_t voxelTypeSize(VoxelType t) { return t == VoxelType::UInt8 ? 1 : (t == VoxelType::UInt16 ? 2 : 4); }

std::string spacingProblem(const std::array<double, 3>& sp) {
  double lo = INFINITY, hi = 0;
  for (double s : sp) {
    if (!std::isfinite(s) || !(s >= kMinSpacing && s <= kMaxSpacing))
      return "spacing " + std::to_string(s) + " must be finite and in [1e-30, 1e30]";
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  // Beyond this the thinnest axis is far below one pixel and the volume renders as nothing.
  if (hi / lo > kMaxSpacingRatio)
    return "spacing ratio largest/smallest is " + std::to_string(hi / lo) + ", must be <= 1e6";
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

uint64_t volumeLoadBytes(const std::array<int, 3>& dims, size_t file_bytes_per_voxel) {
  const uint64_t n = (uint64_t)std::max(dims[0], 0) * (uint64_t)std::max(dims[1], 0) * (uint64_t)std::max(dims[2], 0);
  return n * (sizeof(float) + file_bytes_per_voxel);  // <= 2^48 * 8: no overflow
}

uint64_t physicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size : UINT64_MAX;
}

std::string memoryProblem(const std::array<int, 3>& dims, size_t file_bytes_per_voxel) {
  const uint64_t need = volumeLoadBytes(dims, file_bytes_per_voxel), have = physicalMemoryBytes();
  if (need <= have) return "";
  std::string m = "[";  // built by appending: GCC 12 warns falsely (-Wrestrict) on "lit" + string&&
  m += std::to_string(dims[0]) + ", " + std::to_string(dims[1]) + ", " + std::to_string(dims[2]);
  m += "] voxels need " + std::to_string(need) + " bytes (" + std::to_string(need >> 30);
  m += " GiB) to load, more than this machine's " + std::to_string(have) + " bytes of memory";
  return m;
}

namespace {

size_t typeSize(VoxelType t) { return voxelTypeSize(t); }

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": " + what);
}

void checkGeometry(const std::string& file, const std::array<int, 3>& dims, const std::array<double, 3>& sp) {
  for (int i = 0; i < 3; ++i) {
    if (dims[i] <= 0) fail(file, "dims must be positive, got " + std::to_string(dims[i]));
  }
  if (std::string p = spacingProblem(sp); !p.empty()) fail(file, p);
}

template <class T>
T readLE(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
  }
  return v;
}

// Runs body(z0, z1) over slabs of z on up to four threads, at least 8 slices each.
template <class F>
void parallelZ(int nz, F body) {
  parallelRanges(nz, threadCount(0, std::min(4, std::max(1, nz / 8))),
                 [&](long long z0, long long z1) { body((int)z0, (int)z1); });
}

}  // namespace

Volume loadRawVolume(const RawVolumeSpec& spec) {
  const std::string& f = spec.file;
  checkGeometry(f, spec.dims, spec.spacing);
  if (spec.has_range && !(spec.range[0] < spec.range[1]))
    fail(f, "range must satisfy min < max, got [" + std::to_string(spec.range[0]) + ", " +
                std::to_string(spec.range[1]) + "]");
  if (std::string p = notRegularFile(f); !p.empty()) fail(f, p);
  const size_t count = (size_t)spec.dims[0] * spec.dims[1] * spec.dims[2];
  const size_t ts = typeSize(spec.type);
  const uintmax_t expected = (uintmax_t)count * ts;
  std::error_code ec;
  const uintmax_t actual = std::filesystem::file_size(f, ec);
  if (ec) fail(f, "cannot read size: " + ec.message());
  if (actual != expected)
    fail(f, "file size is " + std::to_string(actual) + " bytes but dims " + std::to_string(spec.dims[0]) +
                " x " + std::to_string(spec.dims[1]) + " x " + std::to_string(spec.dims[2]) + " x " +
                std::to_string(ts) + " bytes/voxel need " + std::to_string(expected) + " bytes");
  // Before allocating: a sparse or huge file would otherwise end in a bare std::bad_alloc.
  if (std::string p = memoryProblem(spec.dims, ts); !p.empty()) fail(f, p);
  std::vector<unsigned char> raw(expected);
  std::ifstream in(f, std::ios::binary);
  if (!in || !in.read(reinterpret_cast<char*>(raw.data()), (std::streamsize)expected))
    fail(f, "read failed");

  Volume v;
  v.dims = spec.dims;
  v.spacing = spec.spacing;
  v.values.resize(count);
  float mn = INFINITY, mx = -INFINITY;
  if (spec.type == VoxelType::UInt8) {
    for (size_t i = 0; i < count; ++i) v.values[i] = (float)(raw[i]);
  } else if (spec.type == VoxelType::UInt16) {
    for (size_t i = 0; i < count; ++i) v.values[i] = (float)readLE<uint16_t>(&raw[2 * i]);
  } else {
    for (size_t i = 0; i < count; ++i) {
      float x = readLE<float>(&raw[4 * i]);
      if (!std::isfinite(x)) {
        size_t nx = spec.dims[0], ny = spec.dims[1];
        fail(f, "non-finite value " + std::to_string(x) + " at voxel (" + std::to_string(i % nx) + ", " +
                    std::to_string(i / nx % ny) + ", " + std::to_string(i / (nx * ny)) + "), linear index " +
                    std::to_string(i));
      }
      v.values[i] = x;
    }
  }
  for (float x : v.values) mn = std::min(mn, x), mx = std::max(mx, x);
  // Like ParaView: with no declared range, colours and opacity span the data's own values.
  const double lo = spec.has_range ? spec.range[0] : mn, hi = spec.has_range ? spec.range[1] : mx;
  v.data_range = {mn, mx};
  v.mapped_range = {lo, hi};
  // Normalise in double; a constant volume (lo == hi) maps to 0 everywhere.
  const double scale = hi > lo ? 1.0 / (hi - lo) : 0.0;
  for (float& x : v.values) x = (float)std::clamp((x - lo) * scale, 0.0, 1.0);
  return v;
}

namespace {

// Smooth bump: 1 inside |d| <= inner, cosine fall-off to exactly 0 at |d| >= outer.
double bump(double d, double inner, double outer) {
  d = std::abs(d);
  if (d <= inner) return 1.0;
  if (d >= outer) return 0.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * (d - inner) / (outer - inner)));
}

void hollowShell(Volume& v) {
  const int n = v.dims[0];
  // Coordinates in [-1, 1] across the box; shell radius 0.75, total thickness 0.1 (5% of the edge).
  parallelZ(n, [&](int z0, int z1) {
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          double u = 2.0 * (x + 0.5) / n - 1, w = 2.0 * (y + 0.5) / n - 1, t = 2.0 * (z + 0.5) / n - 1;
          double r = std::sqrt(u * u + w * w + t * t);
          // Shell peaks at 0.5 and the core at 1.0, so a transfer function can tell them apart.
          double s = 0.5 * bump(r - 0.75, 0.02, 0.05) + bump(r, 0.10, 0.16);
          v.values[v.index(x, y, z)] = (float)std::min(1.0, s);
        }
  });
}

void marschnerLobb(Volume& v) {
  const int n = v.dims[0];
  constexpr double kFm = 6.0, kAlpha = 0.25, kPi = std::numbers::pi;
  parallelZ(n, [&](int z0, int z1) {
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          double u = 2.0 * (x + 0.5) / n - 1, w = 2.0 * (y + 0.5) / n - 1, t = 2.0 * (z + 0.5) / n - 1;
          double rho = std::cos(2 * kPi * kFm * std::cos(kPi * std::sqrt(u * u + w * w) / 2));
          double s = (1 - std::sin(kPi * t / 2) + kAlpha * (1 + rho)) / (2 * (1 + kAlpha));
          v.values[v.index(x, y, z)] = (float)std::clamp(s, 0.0, 1.0);
        }
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

void noiseCloud(Volume& v, uint32_t seed) {
  const int n = v.dims[0];
  constexpr int kOctaves = 4;
  std::vector<Lattice> oct;
  for (int o = 0; o < kOctaves; ++o) oct.emplace_back(4 << o, splitmix64(seed) + (uint64_t)o * 7919);
  parallelZ(n, [&](int z0, int z1) {
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          double p[3] = {(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n};
          double sum = 0, amp = 0.5;
          for (const Lattice& L : oct) {
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
            sum += amp * lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
            amp *= 0.5;
          }
          // Fade towards the box faces so the cloud floats in empty space; threshold gives exact zeros.
          double u = 2 * p[0] - 1, w = 2 * p[1] - 1, t = 2 * p[2] - 1;
          double env = bump(std::sqrt(u * u + w * w + t * t), 0.45, 1.0);
          double s = (sum / 0.9375) * env;  // fBm of 4 octaves spans [0, 0.9375]
          v.values[v.index(x, y, z)] = (float)std::clamp((s - 0.33) / 0.4, 0.0, 1.0);
        }
  });
}

}  // namespace

Volume generateVolume(const GeneratorSpec& spec) {
  if (spec.size < 2) throw std::invalid_argument("generator '" + spec.name + "': size must be >= 2, got " + std::to_string(spec.size));
  if (spec.size > 2048) throw std::invalid_argument("generator '" + spec.name + "': size must be <= 2048, got " + std::to_string(spec.size));
  if (std::string p = spacingProblem(spec.spacing); !p.empty()) throw std::invalid_argument("generator: " + p);
  const std::array<int, 3> dims{spec.size, spec.size, spec.size};
  if (std::string p = memoryProblem(dims, 0); !p.empty()) throw std::invalid_argument("generator: " + p);
  Volume v;
  v.dims = {spec.size, spec.size, spec.size};
  v.spacing = spec.spacing;
  v.values.assign(v.voxelCount(), 0.0f);
  if (spec.name == "hollow-shell") hollowShell(v);
  else if (spec.name == "marschner-lobb") marschnerLobb(v);
  else if (spec.name == "noise-cloud") noiseCloud(v, spec.seed);
  else throw std::invalid_argument("unknown generator '" + spec.name + "' (hollow-shell | marschner-lobb | noise-cloud)");
  const auto [mn, mx] = std::minmax_element(v.values.begin(), v.values.end());
  v.data_range = {*mn, *mx};
  v.mapped_range = {0, 1};
  return v;
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
