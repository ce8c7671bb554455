// Raycaster: per-frame setup (screen footprint of the brick, classification table),
// image tiles pulled by worker threads from an atomic counter, per-pixel ray spans.
#include "renderer/volume/raycaster.h"

#include "common/clock.h"
#include "common/parallel.h"

#include <algorithm>
#include <bit>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "common/max_intensity.h"
#include "renderer/volume/depth_bounds.h"
#include "renderer/volume/kernels.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/occupancy.h"
#include "renderer/volume/per_volume.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/tf_table.h"
#include "renderer/volume/volume_accel.h"

namespace tessera::renderer {

struct Raycaster::Impl {
  std::shared_ptr<const Volume> volume;
  TransferFunction tf;
  std::shared_ptr<const VolumeAccel> accel;
  MinMaxHierarchy::Emptiness emptiness;
  std::vector<uint64_t> occupancy;  // cellOccupancy of emptiness
  Brick nonempty;  // voxel box holding every sample that can be non-empty (lo == hi: none)
  Shading shading;
  Vec3 light;
  std::shared_ptr<const GradientVolume> gradients;  // with shading (shared by casters of the volume)
  Blend blend = Blend::Composite;
  double max_floor = 0;                // blend: maximum or minimum: MaxIntensity::floor
  MaxSkip max_skip;                    // blend: maximum or minimum, pointing into brick_max
  std::vector<uint16_t> brick_max;
};

Raycaster::Raycaster(std::shared_ptr<const Volume> volume, TransferFunction tf, const Shading& shading,
                     const Vec3& light, Blend blend)
    : impl_(std::make_unique<Impl>()) {
  if (!volume) throw std::invalid_argument("Raycaster: null volume");
  const Volume& v = *volume;
  for (int a = 0; a < 3; ++a)
    if (v.dims[a] <= 0) throw std::invalid_argument("Raycaster: volume dims must be positive");
  if (v.values.size() != v.voxelCount()) throw std::invalid_argument("Raycaster: volume value count != dims product");
  // The kernel's 32-bit lane indices address at most 2^31 values of the bricked copy, which holds
  // 9^3 voxels per 8^3-cell brick: ~1.5 G voxels in one renderer (a larger volume needs more bricks).
  const auto nb = MinMaxHierarchy::blockDims(v.dims);
  const double bricked = (double)nb[0] * nb[1] * nb[2] * VolumeAccel::kBrickSize;
  if (bricked >= 2147483648.0)
    throw std::invalid_argument("Raycaster: " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" +
                                std::to_string(v.dims[2]) +
                                " voxels are more than one renderer can address (2^31 values bricked, about 1.5 G "
                                "voxels): split the volume over more renderers");
  if (tf.points().empty()) throw std::invalid_argument("Raycaster: transfer function has no points");
  impl_->accel = VolumeAccel::forVolume(volume);  // one pass over the values, which also finds non-finite ones
  if (!impl_->accel->all_finite)
    for (size_t i = 0; i < v.values.size(); ++i)
      if (!std::isfinite(v.values[i]))
        throw std::invalid_argument("Raycaster: non-finite volume value at linear index " + std::to_string(i));
  impl_->volume = std::move(volume);
  impl_->tf = std::move(tf);
  impl_->shading = shading;
  impl_->light = light;
  impl_->blend = blend;
  if (isProjection(blend) && shading.on)
    throw std::invalid_argument(std::string("Raycaster: blend ") + blendName(blend) + " is not lit (no shading)");
  if (shading.on) impl_->gradients = perVolume<GradientVolume>(impl_->volume);
  const TransferFunction& f = impl_->tf;
  if (isProjection(blend)) {
    // A block is empty when its values cannot reach the floor: nothing below it shows. The
    // minimum projection searches the complements (common/max_intensity.h): a block's largest
    // complement is 1 less its smallest value.
    const bool minimum = blend == Blend::Minimum;
    const MaxIntensity mip(f, minimum);
    const uint32_t floor_q = mip.floorQ();
    impl_->max_floor = mip.floor();
    impl_->emptiness = impl_->accel->hierarchy.classify(
        [floor_q, minimum](float lo, float hi) { return quantizedUpperBound(minimum ? 1 - lo : hi) < floor_q; });
    // Each brick's largest 16-bit value (complement), exactly: the kernel's skip and its early
    // end compare the values it interpolates (one pass over the bricked copy per volume and map).
    const auto& bricks = impl_->accel->nb;
    const uint16_t* q = impl_->accel->bricked.data();
    impl_->brick_max.resize((size_t)bricks[0] * bricks[1] * bricks[2]);
    for (size_t b = 0; b < impl_->brick_max.size(); ++b, q += VolumeAccel::kBrickSize)
      impl_->brick_max[b] = minimum ? (uint16_t)(65535 - *std::min_element(q, q + VolumeAccel::kBrickSize))
                                    : *std::max_element(q, q + VolumeAccel::kBrickSize);
    const uint16_t top = *std::max_element(impl_->brick_max.begin(), impl_->brick_max.end());
    impl_->max_skip = MaxSkip{impl_->brick_max.data(), top, floor_q, minimum};
  } else {
    impl_->emptiness = impl_->accel->hierarchy.classify([&f](float lo, float hi) { return TfTable::rangeIsEmpty(f, lo, hi); });
    impl_->occupancy = cellOccupancy(*impl_->accel, impl_->emptiness, f);
  }
  // Block b holds the samples at voxel coordinates [8b, 8b+8) (clamped at the border); the
  // cell box [8b, 8b+9) holds them with half a voxel to spare, far above the kernel's float
  // error (< 1e-3 voxel), so samples outside it have exactly zero opacity.
  const auto& e = impl_->emptiness;
  Brick& box = impl_->nonempty;
  box = Brick{{0, 0, 0}, {0, 0, 0}};
  if (!e.allEmpty())
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = e.nonempty_lo[a] * MinMaxHierarchy::kBlock;
      box.hi[a] = std::min(v.dims[a], e.nonempty_hi[a] * MinMaxHierarchy::kBlock + 1);
    }
}

Raycaster::~Raycaster() = default;

namespace {

constexpr int kTile = 32;

// The part of `brick` inside `box` (empty, lo == hi, on an axis where they do not meet).
Brick clippedTo(const Brick& brick, const Brick& box) {
  Brick clip;
  for (int a = 0; a < 3; ++a) {
    clip.lo[a] = std::max(brick.lo[a], box.lo[a]);
    clip.hi[a] = std::max(clip.lo[a], std::min(brick.hi[a], box.hi[a]));
  }
  return clip;
}

// What every worker of one render call reads (nothing here changes while they run).
struct FrameRays {
  const Volume& volume;
  const TransferFunction& tf;
  const Quality& q;
  const RayGenerator& gen;
  const VolumeGeometry& geom;
  const Brick& brick;
  const Brick& clip;      // the part of `brick` that can be non-empty (with skipping)
  bool clipping;          // rays are cut to `clip`; the samples cut off count as skipped
  const DepthBounds* depth;  // per-cell depth bounds of non-empty nodes (perspective + skipping)
  const FastContext& fast;
  const double* max_floor;   // blend: maximum or minimum (the reference's floor); null: composite
  bool minimum;              // blend: minimum (the reference searches the complements)
  const ShadeParams* shade;  // null: unlit
  ImageF& img;
  bool count;  // count the samples skipped outside the rays cast (stats were asked for)
  SpanRow rows;  // raySpans' constants: brick and clip, or brick twice without clipping
};

// One worker thread: casts the rays of the tiles it pulls, counts samples, and tracks the
// rectangle of pixels it made non-transparent. Fast-path rays wait in batches of a tile's
// row and are cast together (castFastBatch).
class TileWorker {
 public:
  explicit TileWorker(const FrameRays& f) : f_(f), ax0_(f.img.width), ay0_(f.img.height) {}

  void castTile(int tx, int ty, int ex, int ey) {
    if (!f_.q.reference && !f_.count) return castTileFast(tx, ty, ex, ey);
    for (int py = ty; py < ey; ++py)
      for (int px = tx; px < ex; ++px) {
        RaySpan span;
        int64_t after = 0;  // samples cut off after the clip box
        if (!spanOf(px, py, span, after)) continue;
        if (f_.q.reference) {
          float* o = f_.img.at(px, py);
          double d[4];
          if (f_.max_floor) castReferenceMaximum(f_.volume, *f_.max_floor, f_.minimum, span, d, counts);
          else castReference(f_.volume, f_.tf, f_.q.step, f_.shade, span, d, counts);
          for (int c = 0; c < 4; ++c) o[c] = (float)d[c];
          mark(px, py);
        } else {
          pending_[n_pending_] = Pending{px, py, after};
          spans_[n_pending_++] = span;
          if (n_pending_ == kBatch) flush();
        }
      }
    flush();
  }

  // The fast path without sample counts: rays set up kSpanLanes at a time (raySpans).
  void castTileFast(int tx, int ty, int ex, int ey) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const DepthBounds* depth = f_.depth;  // only with clipping
    for (int py = ty; py < ey; ++py)
      for (int px0 = tx; px0 < ex; px0 += kSpanLanes) {
        const int n = std::min(kSpanLanes, ex - px0);
        double lo[kSpanLanes], hi[kSpanLanes];
        unsigned wanted = 0;
        for (int i = 0; i < kSpanLanes; ++i) lo[i] = -inf, hi[i] = inf;  // raySpans reads every lane
        for (int i = 0; i < n; ++i) {
          if (depth) {  // a cell with no non-empty node: no ray to set up
            const size_t ci = depth->cell(px0 + i, py);
            if (!(depth->lo[ci] <= depth->hi[ci])) continue;
            lo[i] = depth->lo[ci], hi[i] = depth->hi[ci];
          }
          wanted |= 1u << i;
        }
        if (!wanted) continue;
        for (unsigned hits = raySpans(f_.rows, px0, py, n, lo, hi, lanes_) & wanted; hits; hits &= hits - 1) {
          const int i = std::countr_zero(hits);
          pending_[n_pending_] = Pending{px0 + i, py, 0};
          spans_[n_pending_++] = lanes_[i];
          if (n_pending_ == kBatch) flush();
        }
      }
    flush();
  }

  Rect active() const { return ax1_ < 0 ? Rect{} : Rect{ax0_, ay0_, ax1_ - ax0_ + 1, ay1_ - ay0_ + 1}; }
  SampleCounts counts;

 private:
  struct Pending {
    int px, py;
    int64_t after;
  };
  // Rays cast in one castFastBatch call: a tile's row.
  static constexpr int kBatch = kTile;

  // The samples of pixel (px, py) to cast; false if there are none (with f_.count, those
  // skipped are counted: exact, but it costs a brick's renderer 6% in a farm, which needs no counts).
  bool spanOf(int px, int py, RaySpan& span, int64_t& after) {
    const double step = f_.q.step;
    const double offset = f_.rows.jitter ? pixelJitter(px, py) : 0.5;
    if (!f_.clipping) return raySpan(f_.geom, f_.gen.pixelRay(px, py), f_.brick, step, span, offset);
    const DepthBounds* depth = f_.depth;
    const size_t ci = depth ? depth->cell(px, py) : 0;
    if (depth && !(depth->lo[ci] <= depth->hi[ci])) {  // no non-empty node here
      if (f_.count) counts.skipped += (uint64_t)spanSamples(f_.geom, f_.gen.pixelRay(px, py), f_.brick, step, offset);
      return false;
    }
    constexpr double inf = std::numeric_limits<double>::infinity();
    int64_t before = 0;
    const bool hit = raySpanClipped(f_.geom, f_.gen.pixelRay(px, py), f_.brick, f_.clip, step, span,
                                    f_.count ? &before : nullptr, f_.count ? &after : nullptr,
                                    depth ? depth->lo[ci] : -inf, depth ? depth->hi[ci] : inf, offset);
    counts.skipped += (uint64_t)before;
    if (!hit) counts.skipped += (uint64_t)after;
    return hit;
  }

  void mark(int px, int py) {
    if (f_.img.at(px, py)[3] > 0) {
      ax0_ = std::min(ax0_, px), ax1_ = std::max(ax1_, px);
      ay0_ = std::min(ay0_, py), ay1_ = std::max(ay1_, py);
    }
  }

  void finish(const Pending& p, bool terminated) {
    // Samples cut off after a terminated ray count as terminated, as without the clip.
    (terminated ? counts.terminated : counts.skipped) += (uint64_t)p.after;
    mark(p.px, p.py);
  }

  void flush() {
    if (n_pending_ == 0) return;  // also: the reference path, which has no fast context
    float* outs[kBatch];
    bool terminated[kBatch];
    for (int i = 0; i < n_pending_; ++i) outs[i] = f_.img.at(pending_[i].px, pending_[i].py);
    if (f_.fast.maximum) {
      for (int i = 0; i < n_pending_; ++i) terminated[i] = castMaximum(f_.fast, spans_[i], outs[i], counts);
    } else {
      castFastBatch(f_.fast, spans_, outs, n_pending_, counts, terminated);
    }
    for (int i = 0; i < n_pending_; ++i) finish(pending_[i], terminated[i]);
    n_pending_ = 0;
  }

  const FrameRays& f_;
  int ax0_, ay0_, ax1_ = -1, ay1_ = -1;
  Pending pending_[kBatch];
  RaySpan spans_[kBatch];
  RaySpan lanes_[kSpanLanes];  // raySpans' output, a member: initialized once, not per call
  int n_pending_ = 0;
};

}  // namespace

ImageF Raycaster::render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                         RenderStats* stats, Rect* active, ImageF recycled) const {
  const auto start = std::chrono::steady_clock::now();
  const Volume& v = *impl_->volume;
  checkRenderArguments("Raycaster::render", v, width, height, brick, opt.quality);
  const Quality q = samplingQuality(opt.quality, v);

  const RayGenerator gen(cam, width, height);  // validates the camera
  const VolumeGeometry geom(v);
  ImageF img = takeRecycled(width, height, std::move(recycled));
  const Rect fp = brickFootprint(gen, geom, brick, width, height);

  std::optional<ShadeParams> shade;
  if (impl_->shading.on) shade = shadeParams(impl_->shading, impl_->light, geom.cell);
  std::optional<TfTable> table;
  std::optional<HighlightTable> highlight;
  FastContext fast;
  if (!q.reference) {
    fast.shade = shade ? &*shade : nullptr;
    fast.gradients = impl_->gradients.get();
    if (shade) fast.highlight = &highlight.emplace(shade->shininess);
    if (impl_->blend == Blend::Composite) table.emplace(impl_->tf, q.step);  // a projection maps no samples
    fast.volume = &v;
    fast.accel = impl_->accel.get();
    fast.table = table ? &*table : nullptr;
    fast.emptiness = &impl_->emptiness;
    fast.occupancy = impl_->occupancy.empty() ? nullptr : impl_->occupancy.data();
    if (isProjection(impl_->blend)) fast.maximum = &impl_->max_skip;
    fast.skip = q.skip_empty;
    fast.early_termination = (float)std::min(q.early_termination, 2.0);
  }

  // With skipping, rays are cut to the box that can be non-empty (same sample grid, so the
  // image is unchanged); samples outside it count as skipped.
  const bool clipping = !q.reference && q.skip_empty;
  const Brick clip = clipping ? clippedTo(brick, impl_->nonempty) : brick;

  // Perspective rays with skipping: per-cell depth bounds of the non-empty nodes.
  std::optional<DepthBounds> depth;
  if (clipping && !cam.orthographic && clip.lo[0] < clip.hi[0] && clip.lo[1] < clip.hi[1] && clip.lo[2] < clip.hi[2])
    depth = depthBounds(gen, geom, cam.eye, impl_->accel->hierarchy, impl_->emptiness, clip, width, height,
                        threadCount(opt.threads, 1 << 30));

  const int tiles_x = (fp.w + kTile - 1) / kTile, tiles_y = (fp.h + kTile - 1) / kTile;
  const int tile_count = fp.empty() ? 0 : tiles_x * tiles_y;
  std::atomic<int> next{0};
  std::mutex mu;
  SampleCounts total;
  Rect act;

  const double* max_floor = isProjection(impl_->blend) ? &impl_->max_floor : nullptr;
  const FrameRays rays{v, impl_->tf, q, gen, geom, brick, clip, clipping, depth ? &*depth : nullptr, fast, max_floor,
                       impl_->blend == Blend::Minimum,
                        shade ? &*shade : nullptr, img, stats != nullptr,
                        SpanRow(gen, geom, brick, clipping ? clip : brick, q.step, q.jitter && !q.reference)};
  auto worker = [&] {
    TileWorker w(rays);
    try {
      for (int t = next.fetch_add(1); t < tile_count; t = next.fetch_add(1)) {
        const int tx = fp.x + (t % tiles_x) * kTile, ty = fp.y + (t / tiles_x) * kTile;
        w.castTile(tx, ty, std::min(fp.x + fp.w, tx + kTile), std::min(fp.y + fp.h, ty + kTile));
      }
    } catch (...) {
      next.store(tile_count);  // the other workers stop at their next tile; runParts rethrows
      throw;
    }
    std::lock_guard lock(mu);
    total.taken += w.counts.taken;
    total.skipped += w.counts.skipped;
    total.terminated += w.counts.terminated;
    act = unite(act, w.active());
  };

  runParts(threadCount(opt.threads, std::max(1, tile_count)), [&](unsigned) { worker(); });

  if (active) *active = act;
  if (stats) {
    stats->samples = total.taken;
    stats->samples_skipped = total.skipped;
    stats->samples_terminated = total.terminated;
    stats->ms = msSince(start);
  }
  return img;
}

}  // namespace tessera::renderer
