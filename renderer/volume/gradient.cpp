// Gradients for shading (see gradient.h).
#include "renderer/volume/gradient.h"

#include <algorithm>
#include <cmath>

#include "common/parallel.h"
#include "renderer/volume/kernels.h"

namespace tessera::renderer {

namespace {

// G of voxel (x, y, z) on one axis: central inside, one-sided at a face, 0 on a 1-voxel axis.
inline double voxelGradient(const Volume& v, int x, int y, int z, int axis) {
  int lo[3] = {x, y, z}, hi[3] = {x, y, z};
  const int n = v.dims[axis];
  lo[axis] = std::max(0, lo[axis] - 1);
  hi[axis] = std::min(n - 1, hi[axis] + 1);
  const int span = hi[axis] - lo[axis];
  if (span == 0) return 0;
  return ((double)v.at(hi[0], hi[1], hi[2]) - (double)v.at(lo[0], lo[1], lo[2])) / span;
}

void normalize(double v[3]) {
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int a = 0; a < 3; ++a) v[a] = len > 0 ? v[a] / len : 0;
}

}  // namespace

void sampleGradient(const Volume& v, double ux, double uy, double uz, double g[3]) {
  int i[3];
  double f[3];
  trilinearCorner(ux, v.dims[0], i[0], f[0]);
  trilinearCorner(uy, v.dims[1], i[1], f[1]);
  trilinearCorner(uz, v.dims[2], i[2], f[2]);
  g[0] = g[1] = g[2] = 0;
  for (int c = 0; c < 8; ++c) {
    const int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    double w = 1;
    int at[3];
    for (int a = 0; a < 3; ++a) {
      w *= d[a] ? f[a] : 1 - f[a];
      at[a] = std::min(i[a] + d[a], v.dims[a] - 1);
    }
    for (int a = 0; a < 3; ++a) g[a] += w * voxelGradient(v, at[0], at[1], at[2], a);
  }
}

GradientVolume::GradientVolume(const Volume& v) : q(4 * v.voxelCount() + 4, 0) {
  const int nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
  // Row by row: the neighbours on y and z are whole rows, chosen once per row.
  auto quantize = [](float g) { return (int16_t)std::lround(std::clamp(g, -1.0f, 1.0f) * kScale); };
  auto fill = [&](long long z0, long long z1) {
    for (int z = (int)z0; z < (int)z1; ++z)
      for (int y = 0; y < ny; ++y) {
        const int y0 = std::max(0, y - 1), y1 = std::min(ny - 1, y + 1);
        const int zl = std::max(0, z - 1), zh = std::min(nz - 1, z + 1);
        const float* row = &v.values[v.index(0, y, z)];
        const float *ylo = &v.values[v.index(0, y0, z)], *yhi = &v.values[v.index(0, y1, z)];
        const float *zlo = &v.values[v.index(0, y, zl)], *zhi = &v.values[v.index(0, y, zh)];
        const float dy = y1 > y0 ? 1.0f / (float)(y1 - y0) : 0.0f, dz = zh > zl ? 1.0f / (float)(zh - zl) : 0.0f;
        int16_t* out = &q[4 * v.index(0, y, z)];
        for (int x = 0; x < nx; ++x, out += 4) {
          const int x0 = std::max(0, x - 1), x1 = std::min(nx - 1, x + 1);
          const float dx = x1 > x0 ? 1.0f / (float)(x1 - x0) : 0.0f;
          out[0] = quantize((row[x1] - row[x0]) * dx);
          out[1] = quantize((yhi[x] - ylo[x]) * dy);
          out[2] = quantize((zhi[x] - zlo[x]) * dz);
        }
      }
  };
  const bool big = nz >= 4 && v.voxelCount() >= (1u << 18);  // threads cost more than small volumes
  parallelRanges(nz, big ? 2 : 1, fill);
}

ShadeParams shadeParams(const Shading& s, const Vec3& light, const std::array<double, 3>& cell) {
  ShadeParams p;
  p.ambient = s.ambient, p.diffuse = s.diffuse, p.specular = s.specular, p.shininess = s.shininess;
  p.light = {light[0], light[1], light[2]};
  normalize(p.light.data());
  p.cell = cell;
  return p;
}

RayLight rayLight(const ShadeParams& p, const std::array<double, 3>& du) {
  RayLight r;
  double eye[3];  // towards the eye, world
  for (int a = 0; a < 3; ++a) eye[a] = -du[a] * p.cell[a];
  normalize(eye);
  const bool headlight = p.light[0] == 0 && p.light[1] == 0 && p.light[2] == 0;
  for (int a = 0; a < 3; ++a) {
    r.inv_cell[a] = 1 / p.cell[a];
    r.l[a] = headlight ? eye[a] : p.light[a];
    r.h[a] = r.l[a] + eye[a];
  }
  normalize(r.h);  // zero if the light is exactly behind the volume: no highlight
  return r;
}

HighlightTable::HighlightTable(double shininess) : values(kEntries + 1) {
  for (int j = 0; j < kEntries; ++j) values[j] = (float)std::pow((double)j / (kEntries - 1), shininess);
  values[kEntries] = 1;
}

}  // namespace tessera::renderer
