// Marching cubes. The 256-case table is derived once from the cube's faces instead of typed
// in: on each face the crossed edges are joined pairwise, an ambiguous face (diagonal corners
// inside) keeps its inside corners apart; the segments close into loops that are fanned into
// triangles. Neighbouring cubes see the same face corners, so the surface has no cracks.
#include "renderer/mesh/marching_cubes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace tessera::renderer {

namespace {

struct CaseTable {
  int edge_a[12], edge_b[12];            // cube corners of each edge (corner bits: x=1, y=2, z=4)
  std::vector<std::array<int, 3>> tris[256];  // triangles as edge ids
};

const CaseTable& caseTable() {
  static const CaseTable table = [] {
    CaseTable t;
    int n = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int v = 0; v < 8; ++v)
        if (!(v & (1 << axis))) {
          t.edge_a[n] = v;
          t.edge_b[n] = v | (1 << axis);
          ++n;
        }
    auto edgeOf = [&](int a, int b) {
      for (int e = 0; e < 12; ++e)
        if ((t.edge_a[e] == a && t.edge_b[e] == b) || (t.edge_a[e] == b && t.edge_b[e] == a)) return e;
      return -1;
    };
    for (int mask = 0; mask < 256; ++mask) {
      int link[12][2];
      int deg[12] = {};
      auto join = [&](int e0, int e1) {
        link[e0][deg[e0]++] = e1;
        link[e1][deg[e1]++] = e0;
      };
      for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
          const int b1 = 1 << ((axis + 1) % 3), b2 = 1 << ((axis + 2) % 3), base = side << axis;
          const int c[4] = {base, base | b1, base | b1 | b2, base | b2};  // cyclic around the face
          int e[4];
          bool in[4];
          int crossed = 0;
          for (int k = 0; k < 4; ++k) {
            e[k] = edgeOf(c[k], c[(k + 1) % 4]);
            in[k] = mask & (1 << c[k]);
          }
          for (int k = 0; k < 4; ++k) crossed += in[k] != in[(k + 1) % 4];
          if (crossed == 2) {
            int found[2], m = 0;
            for (int k = 0; k < 4; ++k)
              if (in[k] != in[(k + 1) % 4]) found[m++] = e[k];
            join(found[0], found[1]);
          } else if (crossed == 4) {
            for (int k = 0; k < 4; ++k)
              if (in[k]) join(e[(k + 3) % 4], e[k]);
          }
        }
      bool seen[12] = {};
      for (int start = 0; start < 12; ++start) {
        if (deg[start] == 0 || seen[start]) continue;
        std::vector<int> loop;
        int prev = -1, cur = start;
        while (!seen[cur]) {
          seen[cur] = true;
          loop.push_back(cur);
          const int next = link[cur][0] != prev ? link[cur][0] : link[cur][1];
          prev = cur;
          cur = next;
        }
        for (size_t k = 1; k + 1 < loop.size(); ++k) t.tris[mask].push_back({loop[0], loop[k], loop[k + 1]});
      }
    }
    return t;
  }();
  return table;
}

// The volume whole in memory.
struct WholeSource {
  const Volume& v;
  const Volume& geometry() const { return v; }
  void need(int) {}
  float at(int x, int y, int z) const { return v.at(x, y, z); }
};

// The volume as z-slabs of whole x-y planes, loaded as the layers of cubes reach them: layer
// k reads planes k-1..k+2 (the cubes' corners and their gradients' neighbours). Each load
// starts where the last ended (a compressed file streams forward, once); the 3 planes
// before a slab are kept for the layers that straddle two slabs.
struct SlabSource {
  const std::function<Volume(const VoxelBox&)>& load;
  std::array<int, 3> dims;
  int layers;
  Volume cur{}, tail{};  // planes [z0, z1) and the 3 (or fewer) before z0
  int z0 = 0, z1 = 0, t0 = 0;
  const Volume& geometry() const { return cur; }
  void need(int k) {
    const int hi = std::min(k + 3, dims[2]);
    const size_t plane = (size_t)dims[0] * dims[1];
    while (z1 == 0 || hi > z1) {
      Volume keep;  // planes [max(0, z1 - 3), z1), from this slab or the tail before it
      const int k0 = std::max(0, z1 - 3);
      keep.dims = {dims[0], dims[1], z1 - k0};
      keep.values.resize(keep.voxelCount());
      for (int z = k0; z < z1; ++z) {
        const Volume& from = z >= z0 ? cur : tail;
        const float* p = &from.values[(size_t)(z - (z >= z0 ? z0 : t0)) * plane];
        std::copy(p, p + plane, &keep.values[(size_t)(z - k0) * plane]);
      }
      tail = std::move(keep), t0 = k0;
      cur = Volume{};  // the slab before is freed before the next is read
      z0 = z1, z1 = std::min(dims[2], z0 + layers + (z0 == 0 ? 3 : 0));
      cur = load(VoxelBox{{0, 0, z0}, {dims[0], dims[1], z1}});
    }
  }
  float at(int x, int y, int z) const { return z >= z0 ? cur.at(x, y, z - z0) : tail.at(x, y, z - t0); }
};

template <class Source>
Mesh march(Source& src, const std::array<int, 3>& dims, float level, std::array<float, 3> color) {
  const CaseTable& table = caseTable();
  const int nx = dims[0], ny = dims[1], nz = dims[2];
  Mesh m;
  if (nx < 2 || ny < 2 || nz < 2) return m;
  src.need(0);
  const Vec3 lo = src.geometry().boxMin(), half = src.geometry().halfExtent();
  const double cell[3] = {2 * half.x / nx, 2 * half.y / ny, 2 * half.z / nz};
  const int dim[3] = {nx, ny, nz};
  auto gradient = [&](const int g[3], double out[3]) {
    for (int a = 0; a < 3; ++a) {
      int p[3] = {g[0], g[1], g[2]}, q[3] = {g[0], g[1], g[2]};
      p[a] = std::min(g[a] + 1, dim[a] - 1);
      q[a] = std::max(g[a] - 1, 0);
      out[a] = (src.at(p[0], p[1], p[2]) - src.at(q[0], q[1], q[2])) / ((p[a] - q[a]) * cell[a]);
    }
  };
  // Vertex ids of the grid edges touching the current layer of cubes (k..k+1): x and y edges in
  // planes k and k+1, z edges between them. Each crossed edge makes exactly one shared vertex.
  constexpr uint32_t kNone = UINT32_MAX;
  const size_t plane = (size_t)nx * ny;
  std::vector<uint32_t> ex[2], ey[2], ez(plane, kNone);
  for (int s = 0; s < 2; ++s) {
    ex[s].assign(plane, kNone);
    ey[s].assign(plane, kNone);
  }
  auto vertex = [&](int i, int j, int k, int edge) -> uint32_t {
    const int a = table.edge_a[edge], b = table.edge_b[edge];
    const int ga[3] = {i + (a & 1), j + ((a >> 1) & 1), k + (a >> 2)};
    const int gb[3] = {i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2)};
    const int axis = (a ^ b) == 1 ? 0 : (a ^ b) == 2 ? 1 : 2;
    const size_t at = (size_t)ga[0] + (size_t)nx * ga[1];
    uint32_t& slot = axis == 0 ? ex[ga[2] - k][at] : axis == 1 ? ey[ga[2] - k][at] : ez[at];
    if (slot != kNone) return slot;
    const float fa = src.at(ga[0], ga[1], ga[2]), fb = src.at(gb[0], gb[1], gb[2]);
    const double t = (level - fa) / (double)(fb - fa);  // fa != fb: the edge is crossed
    double na[3], nb[3], n[3];
    gradient(ga, na);
    gradient(gb, nb);
    double len2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double p = lo[c] + (ga[c] + 0.5 + t * (gb[c] - ga[c])) * cell[c];
      m.positions.push_back((float)p);
      n[c] = -(na[c] + t * (nb[c] - na[c]));
      len2 += n[c] * n[c];
    }
    const double inv = len2 > 0 ? 1 / std::sqrt(len2) : 0;
    for (int c = 0; c < 3; ++c) m.normals.push_back(len2 > 0 ? (float)(n[c] * inv) : (c == 2 ? 1.f : 0.f));
    m.colors.insert(m.colors.end(), color.begin(), color.end());
    slot = (uint32_t)(m.vertexCount() - 1);
    return slot;
  };
  for (int k = 0; k + 1 < nz; ++k) {
    src.need(k);
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        int mask = 0;
        for (int c = 0; c < 8; ++c)
          if (src.at(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)) >= level) mask |= 1 << c;
        for (const auto& tri : table.tris[mask])
          for (int e : tri) m.indices.push_back(vertex(i, j, k, e));
      }
    std::swap(ex[0], ex[1]);
    std::swap(ey[0], ey[1]);
    std::fill(ex[1].begin(), ex[1].end(), kNone);
    std::fill(ey[1].begin(), ey[1].end(), kNone);
    std::fill(ez.begin(), ez.end(), kNone);
  }
  return m;
}

}  // namespace

Mesh marchingCubes(const Volume& vol, float level, std::array<float, 3> color) {
  WholeSource src{vol};
  return march(src, vol.dims, level, color);
}

Mesh marchingCubes(const std::array<int, 3>& dims, const std::function<Volume(const VoxelBox&)>& load, float level,
                   int layers, std::array<float, 3> color) {
  SlabSource src{load, dims, std::max(layers, 1)};
  return march(src, dims, level, color);
}

}  // namespace tessera::renderer
