// Chunking by Morton order and conservative screen rectangles (see chunks.h).
#include "renderer/mesh/chunks.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace tessera::renderer {

namespace {

uint64_t spread10(uint64_t v) {  // 10 bits -> every third bit of 30
  v &= 0x3ff;
  v = (v | (v << 16)) & 0x30000ff;
  v = (v | (v << 8)) & 0x300f00f;
  v = (v | (v << 4)) & 0x30c30c3;
  v = (v | (v << 2)) & 0x9249249;
  return v;
}

}  // namespace

std::vector<Chunk> buildChunks(Mesh& mesh, uint32_t per_chunk) {
  if (per_chunk == 0) throw std::invalid_argument("buildChunks: triangles_per_chunk must be > 0");
  const size_t nt = mesh.triangleCount();
  const Box b = bounds(mesh);
  auto pos = [&](uint32_t v) {
    return Vec3{mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
  };
  std::vector<std::pair<uint64_t, uint32_t>> keys(nt);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    const Vec3 c = (pos(tri[0]) + pos(tri[1]) + pos(tri[2])) * (1.0 / 3);
    uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double ext = b.hi[a] - b.lo[a];
      const double u = ext > 0 ? (c[a] - b.lo[a]) / ext : 0;
      code |= spread10((uint64_t)std::clamp(u * 1023.0, 0.0, 1023.0)) << a;
    }
    keys[t] = {code, (uint32_t)t};
  }
  std::stable_sort(keys.begin(), keys.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<uint32_t> sorted(mesh.indices.size());
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) sorted[3 * t + k] = mesh.indices[3 * keys[t].second + k];
  mesh.indices = std::move(sorted);

  std::vector<Chunk> chunks;
  for (size_t first = 0; first < nt; first += per_chunk) {
    Chunk c;
    c.first_triangle = (uint32_t)first;
    c.triangle_count = (uint32_t)std::min<size_t>(per_chunk, nt - first);
    for (size_t i = 3 * first; i < 3 * (first + c.triangle_count); ++i) c.box.add(pos(mesh.indices[i]));
    chunks.push_back(c);
  }
  return chunks;
}

Rect screenRect(const Box& box, const ViewProjection& vp) {
  const Rect whole{0, 0, vp.width, vp.height};
  if (box.empty()) return {};
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, wmin = 1e300, wmax = -1e300;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p{(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y, (c & 4) ? box.hi.z : box.lo.z};
    const auto q = toClip(vp, p);
    wmin = std::min(wmin, q[3]);
    wmax = std::max(wmax, q[3]);
    if (!(q[3] > 0)) continue;
    xmin = std::min(xmin, q[0] / q[3]);
    xmax = std::max(xmax, q[0] / q[3]);
    ymin = std::min(ymin, q[1] / q[3]);
    ymax = std::max(ymax, q[1] / q[3]);
  }
  if (!vp.orthographic) {
    // w is the depth along the view direction. Wholly in front of the near plane: clipped away
    // (with a margin for GL's float arithmetic). Straddling the eye plane: the projection is
    // unbounded, so take everything.
    if (wmax < vp.near_plane * 0.999) return {};
    if (!(wmin > vp.near_plane * 1e-3)) return whole;
  }
  // Window coordinates; y flipped to Tessera's top-down rows. The margin covers float rounding
  // in GL's transform and MSAA sample positions anywhere inside a pixel.
  const double x0 = (xmin + 1) * 0.5 * vp.width, x1 = (xmax + 1) * 0.5 * vp.width;
  const double y0 = (1 - ymax) * 0.5 * vp.height, y1 = (1 - ymin) * 0.5 * vp.height;
  // Clamped to just outside the image before converting, so huge coordinates cannot overflow.
  auto cl = [](double v, int n) { return (int)std::clamp(v, -1.0, n + 1.0); };
  const int rx0 = cl(std::floor(x0) - 1, vp.width), rx1 = cl(std::ceil(x1) + 1, vp.width);
  const int ry0 = cl(std::floor(y0) - 1, vp.height), ry1 = cl(std::ceil(y1) + 1, vp.height);
  const Rect r{rx0, ry0, rx1 - rx0, ry1 - ry0};
  return intersect(r, whole);
}

std::vector<int> chunksInTile(const std::vector<Chunk>& chunks, const ViewProjection& vp, const Rect& tile) {
  std::vector<int> out;
  for (size_t i = 0; i < chunks.size(); ++i)
    if (!intersect(screenRect(chunks[i].box, vp), tile).empty()) out.push_back((int)i);
  return out;
}

}  // namespace tessera::renderer
