// k-d tree brick split balanced by non-empty voxels, and BSP front-to-back brick ordering.
#include "common/bricks.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tessera {

namespace {

struct Builder {
  std::array<int, 3> dims;
  const std::vector<uint8_t>* mask;  // 1 where the voxel's alpha > 0; null: count all voxels
  BrickTree tree;

  static long long count(const BrickBox& b) {
    return (long long)(b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) * (b.hi[2] - b.lo[2]);
  }

  // Non-empty voxels per slice of `b` along `axis`.
  std::vector<long long> sliceWeights(const BrickBox& b, int axis) const {
    std::vector<long long> w(b.hi[axis] - b.lo[axis], 0);
    if (!mask) return w;
    for (int z = b.lo[2]; z < b.hi[2]; ++z)
      for (int y = b.lo[1]; y < b.hi[1]; ++y) {
        const uint8_t* row = mask->data() + (size_t)dims[0] * (y + (size_t)dims[1] * z);
        for (int x = b.lo[0]; x < b.hi[0]; ++x)
          if (row[x]) w[(axis == 0 ? x : axis == 1 ? y : z) - b.lo[axis]]++;
      }
    return w;
  }

  int build(const BrickBox& b, int k) {
    int id = (int)tree.nodes.size();
    tree.nodes.emplace_back();
    // The longest axis; of equal ones the slowest in the file (z, then y): a brick that spans
    // whole rows and slices is one contiguous read, while cutting x leaves every file page
    // half wanted (measured on a 256^3 float32 step from a cold cache: 4x the system time).
    int axis = 2;
    for (int a = 1; a >= 0; --a)
      if (b.hi[a] - b.lo[a] > b.hi[axis] - b.lo[axis]) axis = a;
    const int len = b.hi[axis] - b.lo[axis];
    if (k <= 1 || len < 2) {
      tree.nodes[id].leaf = (int)tree.bricks.size();
      tree.bricks.push_back(b);
      return id;
    }
    const int kl = k / 2, kr = k - kl;
    const double frac = (double)kl / k;
    std::vector<long long> w = sliceWeights(b, axis);
    long long total = 0;
    for (long long x : w) total += x;
    if (total == 0) {  // nothing visible here: balance plain volume instead
      std::fill(w.begin(), w.end(), 1);
      total = len;
    }
    // The split s in [1, len-1] whose left weight is closest to frac * total.
    int best = 1;
    double best_err = INFINITY;
    long long acc = 0;
    for (int s = 1; s < len; ++s) {
      acc += w[s - 1];
      double err = std::abs((double)acc - frac * (double)total);
      if (err < best_err) best_err = err, best = s;
    }
    BrickBox lb = b, rb = b;
    lb.hi[axis] = rb.lo[axis] = b.lo[axis] + best;
    // Never ask a child for more bricks than it has voxels.
    int kl2 = (int)std::min<long long>(kl, count(lb)), kr2 = (int)std::min<long long>(kr, count(rb));
    int left = build(lb, kl2);
    int right = build(rb, kr2);
    BrickTree::Node& node = tree.nodes[id];
    node.axis = axis;
    node.split = b.lo[axis] + best;
    node.left = left;
    node.right = right;
    return id;
  }
};

}  // namespace

BrickTree splitBricks(const Volume& v, int n, const TransferFunction* tf) {
  if (n < 1) throw std::invalid_argument("splitBricks: n must be >= 1, got " + std::to_string(n));
  if (v.dims[0] <= 0 || v.dims[1] <= 0 || v.dims[2] <= 0 || v.values.size() != v.voxelCount())
    throw std::invalid_argument("splitBricks: empty or inconsistent volume");
  std::vector<uint8_t> mask;
  if (tf) {
    mask.resize(v.voxelCount());
    // Classify each distinct value once: raw volumes hold few of them, generators many, both fine.
    float last = NAN;
    uint8_t last_m = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
      float s = v.values[i];
      if (s != last) last = s, last_m = tf->eval(s)[3] > 0;
      mask[i] = last_m;
    }
  }
  return splitMask(v.dims, tf ? &mask : nullptr, n);
}

BrickTree splitMask(const std::array<int, 3>& dims, const std::vector<uint8_t>* mask, int n) {
  if (n < 1) throw std::invalid_argument("splitBricks: n must be >= 1, got " + std::to_string(n));
  Builder b{dims, mask, {}};
  const long long total = (long long)dims[0] * dims[1] * dims[2];
  b.build(BrickBox{{0, 0, 0}, dims}, (int)std::min<long long>(n, total));
  return std::move(b.tree);
}

BrickTree scaleBricks(BrickTree t, int edge, const std::array<int, 3>& dims) {
  for (BrickBox& b : t.bricks)
    for (int a = 0; a < 3; ++a) b.lo[a] = std::min(dims[a], b.lo[a] * edge), b.hi[a] = std::min(dims[a], b.hi[a] * edge);
  for (BrickTree::Node& node : t.nodes)
    if (node.axis >= 0) node.split = std::min(dims[node.axis], node.split * edge);
  return t;
}

std::vector<int> BrickTree::visibilityOrder(const Volume& v, const Camera& cam) const {
  std::vector<int> order;
  if (nodes.empty()) return order;
  const Vec3 lo = v.boxMin(), hi = v.boxMax();
  const Vec3 view = cam.target - cam.eye;
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const Node& n = nodes[stack.back()];
    stack.pop_back();
    if (n.leaf >= 0) {
      order.push_back(n.leaf);
      continue;
    }
    // Voxel i covers [i, i+1)/dims of the box, so split index s is the plane at s/dims.
    const int a = n.axis;
    const double plane = lo[a] + (hi[a] - lo[a]) * n.split / v.wholeDims()[a];
    // Low side first if the eye is below the plane (perspective) or rays travel toward +axis (ortho).
    const bool low_first = cam.orthographic ? view[a] >= 0 : cam.eye[a] < plane;
    // Stack: push the far child first so the near one is visited next.
    stack.push_back(low_first ? n.right : n.left);
    stack.push_back(low_first ? n.left : n.right);
  }
  return order;
}

}  // namespace tessera
