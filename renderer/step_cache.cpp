#include "renderer/step_cache.h"

#include <optional>

#include <algorithm>
#include <utility>

#include "common/clock.h"
#include "common/net/log.h"
#include "renderer/volume/volume_accel.h"

namespace tessera::renderer {
namespace {

uint64_t floorMod(long long a, long long m) { return (uint64_t)(((a % m) + m) % m); }

}  // namespace

StepCache::StepCache(const Scene& scene, BackendKind backend, uint64_t budget_bytes)
    : scene_(scene), backend_(backend), budget_(budget_bytes) {
  const auto* raw = std::get_if<RawVolumeSpec>(&scene_.volume);
  if (raw && raw->gzip && scene_.series.steps > 1 && scene_.series.files.empty()) stream_ = std::make_unique<VolumeReader>(scene_);
  // Only a series prefetches; the cpu backend's hierarchy is built there too (osmesa's GL
  // objects belong to the render thread's context: built on first use there).
  if (scene_.series.steps > 1) thread_ = std::thread([this] { prefetchLoop(); });
}

StepCache::~StepCache() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

uint64_t StepCache::entryBytes() const { return bytesFor(box_.hi[0] - box_.lo[0], box_.hi[1] - box_.lo[1], box_.hi[2] - box_.lo[2]); }

// A held step's memory: its float values, the cpu caster's bricked uint16 copy (volume_accel.h)
// and, when shading, its 8-byte gradients.
uint64_t StepCache::bytesFor(int nx, int ny, int nz) const {
  constexpr int B = MinMaxHierarchy::kBlock;
  const uint64_t voxels = (uint64_t)nx * ny * nz;
  const uint64_t bricks = (uint64_t)((nx + B - 1) / B) * ((ny + B - 1) / B) * ((nz + B - 1) / B);
  return voxels * (sizeof(float) + (scene_.shading.on ? 8 : 0)) +
         (backend_ == BackendKind::Cpu ? bricks * VolumeAccel::kBrickSize * sizeof(uint16_t) : 0);
}

uint64_t StepCache::heldBytes() const {  // the shown step is not the budget's: it is held whatever the budget
  uint64_t b = 0;
  for (const auto& [s, e] : held_) b += s == current_ ? 0 : e.bytes;
  return b;
}

// A loaded step joins the cache, which then evicts down to its budget again (the shown step
// may have moved on while it loaded).
std::map<int, StepCache::Entry>::iterator StepCache::keep(int step, Entry&& e) {
  stats_.bytes_read += e.file_bytes;
  auto it = held_.insert_or_assign(step, std::move(e)).first;
  makeRoom(0, 0);
  stats_.peak_bytes = std::max(stats_.peak_bytes, heldBytes());
  return it;
}

uint64_t StepCache::distance(int step) const {
  if (current_ < 0) return 0;
  return floorMod((long long)(step - current_) * direction_, std::max(1, scene_.series.steps));
}

bool StepCache::makeRoom(uint64_t need, uint64_t keep_within) {
  while (heldBytes() + need > budget_) {
    auto far = held_.end();
    for (auto it = held_.begin(); it != held_.end(); ++it)
      if (it->first != current_ && distance(it->first) > keep_within &&
          (far == held_.end() || distance(it->first) > distance(far->first)))
        far = it;
    if (far == held_.end()) return false;
    recycle(std::move(far->second));
    held_.erase(far);
  }
  return true;
}

void StepCache::recycle(Entry&& e) {
  e.caster.reset();  // it holds the volume too
  // Only when nothing else holds it (a frame being rendered keeps its step whole); references
  // are only taken from held_ under mu_, so a count of one stays one.
  if (spare_.empty() && e.volume.use_count() == 1)
    spare_ = std::move(std::const_pointer_cast<Volume>(e.volume)->values);  // made non-const by load()
}

std::vector<float> StepCache::takeSpare() { return std::exchange(spare_, {}); }

std::shared_ptr<const VolumeBackend> StepCache::caster(std::shared_ptr<const Volume> v, const ColorWindow& window) const {
  return makeVolumeBackend(backend_, std::move(v), windowed(scene_.tf, window), scene_.shading, scene_.light, scene_.blend,
                           scene_.crop);
}

StepCache::Entry StepCache::load(int step, const VoxelBox& box, const ColorWindow& window, double& ms,
                                 std::vector<float> storage) {
  const auto t0 = Clock::now();
  Entry e;
  std::shared_ptr<Volume> v;
  if (stream_) {
    std::lock_guard lock(stream_mu_);
    v = std::make_shared<Volume>(stream_->read(box, step, std::move(storage)));
  } else {
    v = std::make_shared<Volume>(loadVolume(scene_, box, step, std::move(storage)));
  }
  if (step > 0 && (v->data_range[0] < v->mapped_range[0] || v->data_range[1] > v->mapped_range[1]))
    spdlog::warn("step {}: values {} .. {} lie outside the range [{}, {}] fixed for the series (step 0's, or "
                 "volume.range): they show as its ends; give volume.range to cover every step",
                 step, v->data_range[0], v->data_range[1], v->mapped_range[0], v->mapped_range[1]);
  e.bytes = bytesFor(v->dims[0], v->dims[1], v->dims[2]);
  const auto* raw = std::get_if<RawVolumeSpec>(&scene_.volume);
  e.file_bytes = raw ? (uint64_t)v->voxelCount() * voxelTypeSize(raw->type) : 0;  // generated: none
  e.volume = v;
  e.window = window;
  if (backend_ == BackendKind::Cpu) e.caster = caster(v, window);
  ms = msSince(t0);
  return e;
}

HeldStep StepCache::get(const VoxelBox& box, int step, const ColorWindow& window) {
  std::unique_lock lock(mu_);
  window_ = window;
  if (!(box == box_)) {
    held_.clear();  // the bricks moved: every held step is of the old window
    spare_ = {};
    box_ = box;
    ++generation_;
  }
  direction_ = current_ >= 0 && step < current_ ? -1 : current_ >= 0 && step > current_ ? 1 : direction_;
  current_ = step;
  makeRoom(0, 0);  // the step shown before now counts against the budget
  // The prefetch thread is reading this step of this box: wait for it rather than read it
  // twice. The frame waited for the file all the same: a miss, its wait the load time.
  double waited_ms = -1;
  if (prefetching_ == step && prefetch_generation_ == generation_) {
    const auto t0 = Clock::now();
    changed_.wait(lock, [&] { return prefetching_ != step || prefetch_generation_ != generation_; });
    waited_ms = msSince(t0);
  }
  auto it = held_.find(step);
  if (it != held_.end() && waited_ms >= 0) {
    ++stats_.misses;
    stats_.load_ms += waited_ms;
  } else if (it != held_.end()) {
    if (scene_.series.steps > 1) ++stats_.hits;
  } else {
    if (scene_.series.steps > 1) ++stats_.misses;
    loading_ = step;
    std::vector<float> storage = takeSpare();
    lock.unlock();
    Entry e;
    double ms = 0;
    try {
      e = load(step, box, window, ms, std::move(storage));
    } catch (const std::exception& ex) {
      lock.lock();
      loading_ = -1;
      changed_.notify_all();
      ++stats_.bad_steps;
      // Said once per bad step (a playing series asks for it again on every pass), again
      // after it has once loaded.
      if (reported_.insert(step).second)
        spdlog::error("step {}: {}; showing step {} instead (bad steps: {}; this step is not said again until it "
                      "loads)", step, ex.what(), last_good_, stats_.bad_steps);
      if (last_good_ < 0) return {};
      current_ = last_good_;  // what is shown in its place
      auto good = held_.find(last_good_);
      if (good == held_.end()) {
        // A budget under one step let it go as this step was asked for (a bad step then had
        // nothing to show and the renderer failed every frame: found by review): read again.
        lock.unlock();
        std::optional<Entry> again;
        double again_ms = 0;
        try {
          again = load(last_good_, box, window, again_ms, {});
        } catch (const std::exception&) {
        }
        lock.lock();
        if (!again) return {};
        stats_.load_ms += again_ms;
        good = keep(last_good_, std::move(*again));
      }
      return shown(last_good_, good->second, window);
    }
    lock.lock();
    loading_ = -1;
    changed_.notify_all();
    stats_.load_ms += ms + std::max(waited_ms, 0.0);  // a prefetch waited for that failed: both
    it = keep(step, std::move(e));
  }
  last_good_ = step;
  reported_.erase(step);
  return shown(step, it->second, window);
}

HeldStep StepCache::shown(int step, Entry& e, const ColorWindow& window) {
  if (!e.caster || !(e.window == window)) {
    // Made before the old one goes: while it lives, the volume's bricked copy and gradients
    // stay in perVolume's cache for the new one.
    e.caster = caster(e.volume, window);
    e.window = window;
  }
  return {step, e.volume, e.caster};
}

void StepCache::prefetch(const std::vector<int>& steps) {
  {
    std::lock_guard lock(mu_);
    wanted_ = steps;
  }
  changed_.notify_all();
}

void StepCache::prefetchLoop() {
  std::unique_lock lock(mu_);
  while (!stop_) {
    // A gzip stream only moves forwards: no step is read ahead while get() reads the shown one.
    if (stream_ && loading_ >= 0) {
      changed_.wait(lock);
      continue;
    }
    // The soonest wanted step that is not held, if it fits without evicting a sooner one.
    int next = -1;
    for (int s : wanted_) {
      if (s < 0 || s >= scene_.series.steps || held_.count(s) || s == loading_ || box_.hi[0] <= box_.lo[0]) continue;
      if (makeRoom(entryBytes(), distance(s))) next = s;
      break;
    }
    if (next < 0) {
      changed_.wait(lock);
      continue;
    }
    prefetching_ = next;
    const uint64_t generation = prefetch_generation_ = generation_;
    const VoxelBox box = box_;  // get() may move the bricks while this loads
    const ColorWindow window = window_;
    std::vector<float> storage = takeSpare();
    lock.unlock();
    if (before_prefetch) before_prefetch(next);
    Entry e;
    double ms = 0;
    bool ok = true;
    try {
      e = load(next, box, window, ms, std::move(storage));
    } catch (const std::exception&) {
      ok = false;  // said (and counted) by get() when the step is shown
    }
    lock.lock();
    prefetching_ = -1;
    stats_.prefetch_ms += ms;
    if (ok && generation == generation_) keep(next, std::move(e));
    std::erase(wanted_, next);  // tried once: a bad step is not read again and again
    changed_.notify_all();
  }
}

StepCacheStats StepCache::take() {
  std::lock_guard lock(mu_);
  StepCacheStats s = stats_;
  stats_.bytes_read = 0;
  stats_.load_ms = stats_.prefetch_ms = 0;
  return s;
}

}  // namespace tessera::renderer
