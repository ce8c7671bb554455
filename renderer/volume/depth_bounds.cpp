#include "renderer/volume/depth_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/parallel.h"

namespace tessera::renderer {

namespace {

// The nodes of z-slices z = part, part + parts, ... into `d` (interleaved slices: the
// non-empty nodes of a scan crowd into some slices).
void addNodeDepths(const RayGenerator& gen, const VolumeGeometry& g, const Vec3& eye, const MinMaxHierarchy& mm,
                   const MinMaxHierarchy::Emptiness& e, const BrickBox& clip, int w, int h, int level, unsigned part,
                   unsigned parts, DepthBounds& d) {
  const int edge = MinMaxHierarchy::kBlock << level;
  const auto n = mm.dims(level);
  for (int z = (int)part; z < n[2]; z += (int)parts)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x) {
        if (e.empty[level][mm.index(level, x, y, z)]) continue;
        const int q[3] = {x, y, z};
        BrickBox b;
        bool overlaps = true;
        for (int a = 0; a < 3; ++a) {
          b.lo[a] = std::max(clip.lo[a], q[a] * edge);
          b.hi[a] = std::min(clip.hi[a], q[a] * edge + edge + 1);
          overlaps = overlaps && b.lo[a] < b.hi[a];
        }
        if (!overlaps) continue;
        const Rect r = brickFootprint(gen, g, b, w, h);
        if (r.empty()) continue;
        double near2 = 0, far2 = 0;
        for (int a = 0; a < 3; ++a) {
          const double p0 = g.plane(a, b.lo[a]), p1 = g.plane(a, b.hi[a]);
          const double dn = std::max({p0 - eye[a], 0.0, eye[a] - p1});
          const double df = std::max(std::fabs(eye[a] - p0), std::fabs(eye[a] - p1));
          near2 += dn * dn, far2 += df * df;
        }
        // Relative slack far above double rounding of t and of the ray's unit length.
        const double t_near = std::sqrt(near2) * (1 - 1e-9), t_far = std::sqrt(far2) * (1 + 1e-9) + 1e-12;
        for (int cy = r.y / DepthBounds::kCell; cy <= (r.y + r.h - 1) / DepthBounds::kCell; ++cy)
          for (int cx = r.x / DepthBounds::kCell; cx <= (r.x + r.w - 1) / DepthBounds::kCell; ++cx) {
            const size_t i = (size_t)cy * d.cols + cx;
            d.lo[i] = std::min(d.lo[i], t_near);
            d.hi[i] = std::max(d.hi[i], t_far);
          }
      }
}

}  // namespace

DepthBounds depthBounds(const RayGenerator& gen, const VolumeGeometry& g, const Vec3& eye, const MinMaxHierarchy& mm,
                        const MinMaxHierarchy::Emptiness& e, const BrickBox& clip, int w, int h, unsigned threads) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  auto blank = [&] {
    DepthBounds d;
    d.cols = (w + DepthBounds::kCell - 1) / DepthBounds::kCell;
    const int rows = (h + DepthBounds::kCell - 1) / DepthBounds::kCell;
    d.lo.assign((size_t)d.cols * rows, inf);
    d.hi.assign(d.lo.size(), -inf);
    return d;
  };
  // The finest level with at most 2^15 nodes keeps this well under a millisecond or two.
  int level = 0;
  auto count = [&](int l) { const auto n = mm.dims(l); return (int64_t)n[0] * n[1] * n[2]; };
  while (level + 1 < mm.levels() && count(level) > (1 << 15)) ++level;
  const unsigned parts = std::max(1u, std::min<unsigned>(threads, (unsigned)mm.dims(level)[2]));
  std::vector<DepthBounds> d(parts);
  runParts(parts, [&](unsigned p) {
    d[p] = blank();
    addNodeDepths(gen, g, eye, mm, e, clip, w, h, level, p, parts, d[p]);
  });
  for (unsigned p = 1; p < parts; ++p)
    for (size_t i = 0; i < d[0].lo.size(); ++i) {
      d[0].lo[i] = std::min(d[0].lo[i], d[p].lo[i]);
      d[0].hi[i] = std::max(d[0].hi[i], d[p].hi[i]);
    }
  return std::move(d[0]);
}

}  // namespace tessera::renderer
