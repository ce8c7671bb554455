// Reference kernel: double precision, exact transfer function evaluation per sample.
#include <algorithm>
#include <cmath>

#include "renderer/volume/kernels.h"

namespace tessera::renderer {

void trilinearCorner(double u, int n, int& i, double& f) {
  u = std::clamp(u, 0.0, (double)(n - 1));
  i = std::clamp((int)u, 0, std::max(0, n - 2));
  f = u - i;
}

double sampleTrilinear(const Volume& v, double ux, double uy, double uz) {
  int ix, iy, iz;
  double fx, fy, fz;
  trilinearCorner(ux, v.dims[0], ix, fx);
  trilinearCorner(uy, v.dims[1], iy, fy);
  trilinearCorner(uz, v.dims[2], iz, fz);
  // A one-voxel axis has no second corner; its weight is 0 there anyway.
  const size_t sx = v.dims[0] > 1 ? 1 : 0;
  const size_t sy = v.dims[1] > 1 ? (size_t)v.dims[0] : 0;
  const size_t sz = v.dims[2] > 1 ? (size_t)v.dims[0] * v.dims[1] : 0;
  const float* p = &v.values[v.index(ix, iy, iz)];
  auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  const double c00 = lerp(p[0], p[sx], fx), c10 = lerp(p[sy], p[sy + sx], fx);
  const double c01 = lerp(p[sz], p[sz + sx], fx), c11 = lerp(p[sz + sy], p[sz + sy + sx], fx);
  return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
}

namespace {
// Lights the straight (not premultiplied) colour c of a sample whose gradient is g.
void shadeColour(const ShadeParams& p, const RayLight& r, const double g[3], double c[3]) {
  double diffuse = 1, highlight = 0;
  if (std::max({std::fabs(g[0]), std::fabs(g[1]), std::fabs(g[2])}) >= kFlatGradient) {
    double len2 = 0, nl = 0, nh = 0;
    for (int a = 0; a < 3; ++a) {
      const double gw = g[a] * r.inv_cell[a];
      len2 += gw * gw, nl += gw * r.l[a], nh += gw * r.h[a];
    }
    const double len = std::sqrt(len2);
    diffuse = std::fabs(nl) / len;
    highlight = std::pow(std::fabs(nh) / len, p.shininess);
  }
  for (int ch = 0; ch < 3; ++ch)
    c[ch] = std::min(1.0, c[ch] * (p.ambient + p.diffuse * diffuse) + p.specular * highlight);
}
}  // namespace

void castReference(const Volume& v, const TransferFunction& tf, double step, const ShadeParams* shade,
                   const RaySpan& span, double out[4], SampleCounts& counts) {
  double acc[4] = {0, 0, 0, 0};
  const RayLight light = shade ? rayLight(*shade, span.du) : RayLight{};
  for (int64_t k = span.k_first; k < span.k_end; ++k) {
    const double kd = (double)k;
    const double u[3] = {span.u0[0] + kd * span.du[0], span.u0[1] + kd * span.du[1], span.u0[2] + kd * span.du[2]};
    const double s = sampleTrilinear(v, u[0], u[1], u[2]);
    auto c = tf.eval(s);
    if (c[3] <= 0) continue;  // contributes exactly nothing; saves the pow
    if (shade) {
      double g[3];
      sampleGradient(v, u[0], u[1], u[2], g);
      shadeColour(*shade, light, g, c.data());
    }
    const double a = correctOpacity(c[3], step);
    const double w = (1.0 - acc[3]) * a;
    acc[0] += w * c[0];
    acc[1] += w * c[1];
    acc[2] += w * c[2];
    acc[3] += w;
  }
  counts.taken += (uint64_t)(span.k_end - span.k_first);
  for (int i = 0; i < 4; ++i) out[i] = acc[i];
}

}  // namespace tessera::renderer
