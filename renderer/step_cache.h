// A renderer's voxels over time: the window of its bricks (plus ghost voxels) for each time
// step it holds, under a byte budget, and one prefetch thread that loads the steps the
// master will show next off the render path (voxels and, for the cpu backend, the min-max
// hierarchy). Entries are evicted by playback order: the step farthest ahead of the
// playhead in the direction of play (the one passed longest ago) goes first.
// A static volume is a series of one step: it is loaded once and kept.
#pragma once
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <variant>
#include <vector>

#include "common/scene.h"
#include "renderer/volume/backend.h"

namespace tessera::renderer {

struct HeldStep {
  int step = -1;
  std::shared_ptr<const Volume> volume;
  std::shared_ptr<const VolumeBackend> caster;
};

// What the cache did since the last take(): for a renderer's Stats.
struct StepCacheStats {
  uint32_t hits = 0, misses = 0;  // cumulative
  uint64_t bytes_read = 0;        // file bytes read (loads and prefetches) since the last take
  double load_ms = 0;             // on the render path (misses) since the last take
  double prefetch_ms = 0;         // on the prefetch thread since the last take
  uint64_t bad_steps = 0;         // steps that could not be read (cumulative)
  uint64_t peak_bytes = 0;        // the most held besides the shown step (cumulative peak)
};

class StepCache {
 public:
  // `budget_bytes`: memory of the steps held besides the one shown, the prefetched ones
  // included (about 7 bytes a voxel with the cpu backend, 15 when shading).
  StepCache(const Scene& scene, BackendKind backend, uint64_t budget_bytes);
  ~StepCache();
  StepCache(const StepCache&) = delete;
  StepCache& operator=(const StepCache&) = delete;

  // Step `step` of the window `box`: held, or loaded now (a miss). A step that cannot be
  // read is logged and counted, and the last good step is returned instead (nullptr volume
  // when there is none: the caller fails the frame). A new box drops every held step.
  // Its caster renders the scene's colour map through `window`: a held step's caster of
  // another window is made again (the cpu backend keeps its bricked voxels and gradients and
  // classifies them for the map again: 15-25 ms for half of a 256^3 volume; the osmesa
  // backend makes its context and volume texture again), and steps read ahead from then on
  // are made for it. The last good step shown instead of a bad one is shown through it too.
  HeldStep get(const VoxelBox& box, int step, const ColorWindow& window = {});
  // The steps the master will show next, soonest first: the prefetch thread loads those not
  // held, as the budget allows, and forgets earlier wishes (steps playback has passed).
  void prefetch(const std::vector<int>& steps);
  StepCacheStats take();
  // Called by the prefetch thread (unlocked) before it reads a step: lets a test hold a
  // prefetch in progress. Set before the first prefetch().
  std::function<void(int step)> before_prefetch;

 private:
  struct Entry {
    std::shared_ptr<const Volume> volume;
    std::shared_ptr<const VolumeBackend> caster;
    uint64_t bytes = 0;       // held in memory
    uint64_t file_bytes = 0;  // read from the file for it
    ColorWindow window;       // the caster's
  };
  void prefetchLoop();
  // Loads step `step` of `box` (box_ as the caller read it under mu_) into `storage`, unlocked
  // while reading; throws what loadVolume throws.
  Entry load(int step, const VoxelBox& box, const ColorWindow& window, double& ms, std::vector<float> storage);
  std::shared_ptr<const VolumeBackend> caster(std::shared_ptr<const Volume> v, const ColorWindow& window) const;
  HeldStep shown(int step, Entry& e, const ColorWindow& window);  // e's caster made for `window` if not; under mu_
  // A freed step's samples, for the next load: a step's window costs no page faults and no
  // zeroing (measured: ~5% of a playing renderer's time). Under mu_.
  void recycle(Entry&& e);
  std::vector<float> takeSpare();
  // Frees held steps farther along playback than `keep_within` (and never `current_`) until
  // `need` more bytes fit the budget; false if they still do not.
  bool makeRoom(uint64_t need, uint64_t keep_within);
  uint64_t distance(int step) const;  // steps from the playhead to `step` in the direction of play
  uint64_t entryBytes() const;
  uint64_t bytesFor(int nx, int ny, int nz) const;
  uint64_t heldBytes() const;                                    // under mu_
  std::map<int, Entry>::iterator keep(int step, Entry&& e);  // under mu_

  const Scene& scene_;
  BackendKind backend_;
  uint64_t budget_;
  mutable std::mutex mu_;
  std::condition_variable changed_;
  VoxelBox box_{};
  ColorWindow window_;       // of the last get(): what steps are read ahead for
  uint64_t generation_ = 0;  // bumped with box_: a load of an old box is dropped
  std::map<int, Entry> held_;
  int current_ = -1, direction_ = 1, last_good_ = -1;
  std::set<int> reported_;  // bad steps said since they last loaded
  int loading_ = -1, prefetching_ = -1;  // the step being read by get() and by the prefetch thread
  uint64_t prefetch_generation_ = 0;      // of the box the prefetch thread reads prefetching_ of
  std::vector<int> wanted_;
  std::vector<float> spare_;  // at most one window's samples: taken by the next load
  StepCacheStats stats_;
  // A gzip-compressed 4-D file is one stream: its steps are read through one reader, so step
  // t + 1 continues where step t ended (one step decompressed, not t + 1). Other files are
  // read by a reader of their own per load, the render path's and the prefetch's in parallel.
  std::mutex stream_mu_;
  std::unique_ptr<VolumeReader> stream_;  // under stream_mu_; null when not one stream
  bool stop_ = false;
  std::thread thread_;  // last: started once everything above is ready
};

}  // namespace tessera::renderer
