#include "renderer/stage.h"

#include <chrono>
#include <deque>
#include <map>
#include <optional>

#include "common/cpu.h"
#include "common/volume_summary.h"
#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/wire/pixels.h"
#include "common/wire/protocol.h"
#include "common/net/stage_link.h"
#include "common/net/transport.h"
#include "renderer/tile_render.h"

namespace tessera::renderer {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// What determines a brick's image: a frame with the same key is not rendered again.
struct RenderKey {
  Camera camera;
  Quality quality;
  int width = 0, height = 0;
  BrickBox brick;
  bool operator==(const RenderKey&) const = default;
};

class Stage {
 public:
  Stage(const StageOptions& opt, zmq::context_t& ctx)
      : opt_(opt), ctx_(ctx), link_(ctx, opt.endpoints, proto::Role::Renderer), scene_(opt.scene) {
    if (opt.scene.mesh) {
      tiles_ = std::make_unique<TileRenderer>(opt.scene);
    } else {
      // Before joining, so a bad file is said at once; every window loaded later is
      // normalised with the whole file's range without scanning it again.
      fixVolumeRange(scene_);
    }
  }

  int run(const std::atomic<bool>* stop) {
    if (!link_.join(stop)) {
      if (stop && *stop) return 0;  // stopped (Ctrl-C) while it waited: not a failure to join
      spdlog::error("renderer could not join the master at {}", opt_.endpoints.masterControl());
      return 1;
    }
    spdlog::info("renderer rank={} joined backend={} simd={}", link_.rank(),
                 scene_.mesh ? "osmesa-mesh" : backendName(opt_.backend), isaName(cpuIsa()));
    zmq::pollitem_t items[] = {{link_.sub().handle(), 0, ZMQ_POLLIN, 0}};
    std::deque<proto::FrameParams> queued;
    while (!(stop && *stop)) {
      pollFor(items, 1, std::chrono::milliseconds(queued.empty() ? 100 : 0));
      // Drain before every frame, so frames superseded by a newer epoch or cancelled by an
      // interaction are skipped, not rendered.
      auto published = link_.receive(drops_);
      if (published.shutdown) return 0;
      for (auto& p : published.params) {
        epoch_ = std::max(epoch_, p.epoch);
        first_wanted_ = std::max(first_wanted_, p.first_wanted);
        queued.push_back(std::move(p));
      }
      if (link_.masterLost()) return 1;
      std::erase_if(queued, [&](const auto& p) { return p.epoch != epoch_ || p.frame < first_wanted_; });
      if (queued.empty()) continue;
      renderFrameOrLog(queued.front());
      queued.pop_front();
    }
    return 0;
  }

 private:
  // A frame whose parameters make rendering throw (the master's checks should prevent it)
  // costs that frame, never the renderer: the farm keeps its other frames.
  void renderFrameOrLog(const proto::FrameParams& p) {
    try {
      renderFrame(p);
    } catch (const std::exception& e) {
      ++frames_failed_;
      spdlog::error("frame={} render failed: {} frames_failed={}", p.frame, e.what(), frames_failed_);
    }
  }

  void renderFrame(const proto::FrameParams& p) {
    proto::StageStats st;
    st.role = proto::Role::Renderer;
    st.rank = link_.rank();
    st.frame = p.frame;
    if (const proto::SortFirstWork* work = p.sortFirst()) return renderTiles(p, *work, st);
    renderBricks(p, *p.sortLast(), st);
  }

  void renderBricks(const proto::FrameParams& p, const proto::SortLastWork& work, proto::StageStats& st) {
    if (tiles_) return drops_.drop(~0u, "sort-last FrameParams for a geometry scene");
    holdBricks(p.frame, work, st);
    for (uint32_t b = 0; b < work.bricks.size(); ++b) {
      if (work.bricks[b].renderer != link_.rank()) continue;
      auto t0 = Clock::now();
      const Cached& c = render(p, work.bricks[b].brick, st);
      st.work_ms += msSince(t0);
      st.active = unite(st.active, c.active);
      st.active_pixels += c.active.area();
      auto t1 = Clock::now();
      for (const auto& region : p.regions) sendPiece(p, b, region, c, st);
      st.encode_ms += msSince(t1);
    }
    st.dropped = drops_.total();
    link_.report(proto::encode(st, link_.rank()));
  }

  void renderTiles(const proto::FrameParams& p, const proto::SortFirstWork& work, proto::StageStats& st) {
    if (!tiles_) return drops_.drop(~0u, "sort-first FrameParams for a volume scene");
    auto outputs = tiles_->render(p, work, link_.rank(), st);
    st.images_made = (uint32_t)st.tile_ms.size();
    auto t0 = Clock::now();
    for (auto& o : outputs) {
      const std::string* endpoint = nullptr;
      for (const auto& r : p.regions)
        if (r.compositor == o.compositor) endpoint = &r.endpoint;
      if (!endpoint) continue;
      auto bytes = proto::encode(o.framebuffer, link_.rank(), p.codec);
      st.bytes_raw += o.framebuffer.pixels.size();
      st.bytes_encoded += bytes.size();
      sendBytes(socketFor(*endpoint), std::move(bytes));
    }
    st.encode_ms = msSince(t0);
    st.dropped = drops_.total();
    link_.report(proto::encode(st, link_.rank()));
  }

  // Loads the voxels of this renderer's bricks and their ghost layer unless the window held
  // has them all.
  // Memory follows the bricks, not the volume; a move of bricks costs one load, in the stats.
  void holdBricks(uint64_t frame, const proto::SortLastWork& work, proto::StageStats& st) {
    const auto whole = volumeDims(scene_);
    // Trilinear sampling near a brick face reads one voxel beyond it; its gradient, one more.
    const int ghost = scene_.shading.on ? 2 : 1;
    VoxelBox need{whole, {0, 0, 0}};
    for (const auto& b : work.bricks) {
      if (b.renderer != link_.rank()) continue;
      for (int a = 0; a < 3; ++a) {
        need.lo[a] = std::min(need.lo[a], std::max(0, b.brick.lo[a] - ghost));
        need.hi[a] = std::max(need.hi[a], std::min(whole[a], b.brick.hi[a] + ghost));
      }
    }
    if (need.lo[0] >= need.hi[0]) return;  // no brick of ours this frame
    if (volume_) {
      bool inside = true;
      for (int a = 0; a < 3; ++a)
        inside = inside && need.lo[a] >= volume_->origin[a] && need.hi[a] <= volume_->origin[a] + volume_->dims[a];
      if (inside) return;
    }
    const auto t0 = Clock::now();
    caster_.reset();
    cache_.clear();
    volume_.reset();  // before loading the next: peak memory is one window
    volume_ = std::make_shared<Volume>(loadVolume(scene_, need));
    caster_ = makeVolumeBackend(opt_.backend, volume_, scene_.tf, scene_.shading, scene_.light);
    st.load_ms = msSince(t0);
    spdlog::info("frame={} loaded voxels [{}, {}, {}] .. [{}, {}, {}) ({:.1f} MiB) in {:.0f} ms", frame,
                 need.lo[0], need.lo[1], need.lo[2], need.hi[0], need.hi[1], need.hi[2],
                 (double)volume_->voxelCount() * sizeof(float) / (1 << 20), st.load_ms);
  }

  struct Cached {
    RenderKey key;
    ImageF image;
    Rect active;
  };

  const Cached& render(const proto::FrameParams& p, const BrickBox& brick, proto::StageStats& st) {
    RenderKey key{p.camera, p.quality, p.width, p.height, brick};
    for (auto& c : cache_)
      if (c.key == key) return ++st.images_reused, c;  // unchanged inputs: reuse, do not render again
    ++st.images_made;
    RenderOptions ro;
    ro.quality = p.quality;
    ro.threads = opt_.threads;
    Cached c{key, {}, {}};
    Brick local = brick;  // in the held window's voxel indices
    for (int a = 0; a < 3; ++a) local.lo[a] -= volume_->origin[a], local.hi[a] -= volume_->origin[a];
    // No RenderStats: the farm needs no sample counts, and counting skipped samples costs.
    c.image = caster_->render(p.camera, p.width, p.height, local, ro, nullptr, &c.active);
    if (cache_.size() >= 2) cache_.pop_front();  // a renderer may own two bricks after a failure
    cache_.push_back(std::move(c));
    return cache_.back();
  }

  void sendPiece(const proto::FrameParams& p, uint32_t brick, const proto::CompositorRegion& region,
                 const Cached& c, proto::StageStats& st) {
    proto::Piece piece;
    piece.frame = p.frame;
    piece.epoch = p.epoch;
    piece.renderer = link_.rank();
    piece.brick = brick;
    piece.region = region.region;
    piece.active = intersect(c.active, region.region);
    piece.format = p.format;
    if (!piece.active.empty()) piece.pixels = packPixels(c.image, piece.active, p.format);
    piece.render_ms = st.work_ms;
    auto bytes = proto::encode(piece, link_.rank(), p.codec);
    st.bytes_raw += piece.pixels.size();
    st.bytes_encoded += bytes.size();
    sendBytes(socketFor(region.endpoint), std::move(bytes));
  }

  zmq::socket_t& socketFor(const std::string& endpoint) {
    auto it = pushes_.find(endpoint);
    if (it == pushes_.end()) {
      zmq::socket_t s = makeSocket(ctx_, zmq::socket_type::dealer);
      s.set(zmq::sockopt::routing_id, link_.dataIdentity());  // compositors admit it by this
      s.set(zmq::sockopt::linger, 1000);  // let the last pieces leave at shutdown
      connectTo(s, endpoint);
      it = pushes_.emplace(endpoint, std::move(s)).first;
    }
    return it->second;
  }

  const StageOptions& opt_;
  zmq::context_t& ctx_;
  StageLink link_;
  Scene scene_;                      // the scene, with the data's range fixed once
  std::shared_ptr<Volume> volume_;   // the window of this renderer's bricks
  std::unique_ptr<VolumeBackend> caster_;  // volume scenes (sort-last)
  std::unique_ptr<TileRenderer> tiles_;   // geometry scenes (sort-first)
  std::deque<Cached> cache_;
  std::map<std::string, zmq::socket_t> pushes_;
  uint32_t epoch_ = 0;
  uint64_t first_wanted_ = 0;  // frames below it were cancelled
  uint64_t frames_failed_ = 0;
  DropCounter drops_;
};

}  // namespace

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  Stage s(opt, ctx);
  return s.run(stop);
}

}  // namespace tessera::renderer
