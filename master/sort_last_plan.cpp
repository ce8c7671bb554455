#include "master/sort_last_plan.h"

#include <algorithm>
#include <cmath>

#include <spdlog/spdlog.h>

#include "master/balance.h"

namespace tessera::master {

SortLastPlan::SortLastPlan(VolumeSummary volume, const TransferFunction& tf, bool balance, bool binary_swap,
                           const Crop& crop)
    : volume_(std::move(volume)), tf_(tf), balance_(balance), binary_swap_(binary_swap), crop_(crop) {}

// Bricks are sticky: a renderer keeps its bricks (and the voxels it loaded for them) for
// the whole run. A renderer that joins gets a new split for everyone (balance needs it);
// a lost renderer's bricks go to the owner of their nearest bricks in the k-d tree, so its
// new window is the parent box, and nobody else loads anything (binary swap: see below).
void SortLastPlan::reassign(const Workers& w) {
  const auto alive = [&](uint32_t r) { return std::find(w.renderers.begin(), w.renderers.end(), r) != w.renderers.end(); };
  bool joined = tree_.bricks.empty();
  for (uint32_t r : w.renderers) joined = joined || std::find(owner_.begin(), owner_.end(), r) == owner_.end();
  auto split = [&] {
    tree_ = splitBricks(volume_, std::max<int>(1, (int)w.renderers.size()), tf_, crop_);
    owner_.clear();
    for (size_t i = 0; i < tree_.bricks.size() && i < w.renderers.size(); ++i) owner_.push_back(w.renderers[i]);
  };
  if (joined) return split();
  if (w.renderers.empty()) return;
  std::vector<uint32_t> heirs = owner_;
  for (size_t b = 0; b < heirs.size(); ++b)
    if (!alive(heirs[b])) heirs[b] = nearestAliveOwner((int)b, alive).value_or(w.renderers.front());
  // Binary swap needs one brick per renderer: when a lost one's bricks would go to a renderer
  // that has one, everyone gets a new split instead. (A volume too small for n bricks has
  // fewer, each renderer at most one.)
  std::vector<uint32_t> sorted = heirs;
  std::sort(sorted.begin(), sorted.end());
  if (binary_swap_ && std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    spdlog::info("binary swap: a new split of {} bricks for {} renderers", w.renderers.size(), w.renderers.size());
    return split();
  }
  for (size_t b = 0; b < owner_.size(); ++b)
    if (heirs[b] != owner_[b]) spdlog::info("brick {} of lost renderer {} goes to renderer {}", b, owner_[b], heirs[b]);
  owner_ = std::move(heirs);
}

// The alive owner of a leaf in the subtree of the brick's closest ancestor that has one.
std::optional<uint32_t> SortLastPlan::nearestAliveOwner(int brick, const std::function<bool(uint32_t)>& alive) const {
  std::vector<int> parent(tree_.nodes.size(), -1);
  int node = -1;
  for (int i = 0; i < (int)tree_.nodes.size(); ++i) {
    const auto& n = tree_.nodes[i];
    if (n.leaf == brick) node = i;
    if (n.left >= 0) parent[n.left] = i;
    if (n.right >= 0) parent[n.right] = i;
  }
  for (int up = node >= 0 ? parent[node] : -1; up >= 0; up = parent[up]) {
    std::vector<int> stack{up};
    while (!stack.empty()) {
      const auto& n = tree_.nodes[stack.back()];
      stack.pop_back();
      if (n.leaf >= 0 && alive(owner_[n.leaf])) return owner_[n.leaf];
      if (n.left >= 0) stack.push_back(n.left), stack.push_back(n.right);
    }
  }
  return std::nullopt;
}

void SortLastPlan::fill(proto::FrameParams& p, const Workers& w) {
  auto& work = p.work.emplace<proto::SortLastWork>();
  for (size_t i = 0; i < tree_.bricks.size() && i < owner_.size(); ++i) work.bricks.push_back({owner_[i], tree_.bricks[i]});
  work.order = tree_.visibilityOrder(volume_.shape, p.camera);
  if (binary_swap_) addSwapPlan(work, w);
  std::vector<Rect> active;
  for (const auto& [renderer, f] : balance_ ? last_active_ : decltype(last_active_){}) {
    const int x0 = (int)std::floor(f[0] * p.width), y0 = (int)std::floor(f[1] * p.height);
    active.push_back({x0, y0, (int)std::ceil(f[2] * p.width) - x0, (int)std::ceil(f[3] * p.height) - y0});
  }
  sizes_[p.frame] = {p.width, p.height};
  while (sizes_.size() > 256) sizes_.erase(sizes_.begin());  // frames whose stats never come
  // A binary-swap frame has no regions: the renderers send their finished bands straight to
  // the display, a hop and a decode-and-encode fewer than through a compositor.
  if (!work.swap.empty()) return;
  auto bands = balancedBands(p.width, p.height, (int)w.compositors.size(), active);
  for (size_t i = 0; i < bands.size() && i < w.compositors.size(); ++i)
    p.regions.push_back({w.compositors[i].rank, bands[i], w.compositors[i].endpoint});
}

// One brick per renderer, any count of them (a count that is not a power of two swaps in
// groups of its prime factors: proto::swapRadices); one renderer sends its image straight to
// the display. Direct send when a renderer has no swap socket.
void SortLastPlan::addSwapPlan(proto::SortLastWork& work, const Workers& w) const {
  if (work.bricks.empty()) return;
  for (const auto& b : work.bricks) {
    auto it = std::find(w.renderers.begin(), w.renderers.end(), b.renderer);
    const size_t i = it - w.renderers.begin();
    if (i >= w.renderer_endpoints.size()) return work.swap.clear();
    const std::string& endpoint = w.renderer_endpoints[i];
    for (const auto& s : work.swap)
      if (s.renderer == b.renderer) return work.swap.clear();
    if (endpoint.empty()) return work.swap.clear();
    work.swap.push_back({b.renderer, endpoint});
  }
}

// Whether the frames fill() makes now would go by direct send (addSwapPlan gives up).
bool SortLastPlan::needsCompositors(const Workers& w) const {
  if (!binary_swap_) return true;
  proto::SortLastWork work;
  for (size_t i = 0; i < tree_.bricks.size() && i < owner_.size(); ++i) work.bricks.push_back({owner_[i], tree_.bricks[i]});
  addSwapPlan(work, w);
  return work.swap.empty();
}

void SortLastPlan::stats(const proto::StageStats& s, const Workers&) {
  if (s.role != proto::Role::Renderer || s.frame + 1 < latest_active_frame_) return;
  auto size = sizes_.find(s.frame);
  if (size == sizes_.end()) return;  // not a frame of ours
  if (s.frame + 1 > latest_active_frame_) last_active_.clear();
  latest_active_frame_ = s.frame + 1;
  sizes_.erase(sizes_.begin(), size);
  const auto [w, h] = size->second;
  const Rect& a = s.active;
  if (a.empty()) last_active_.erase(s.rank);
  else last_active_[s.rank] = {(double)a.x / w, (double)a.y / h, (double)(a.x + a.w) / w, (double)(a.y + a.h) / h};
}

}  // namespace tessera::master
