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
#include "renderer/step_cache.h"
#include "renderer/swap_exchange.h"
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
  int step = 0;
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
      // normalised with the whole file's range (a series: step 0's) without scanning it again.
      fixVolumeRange(scene_);
      steps_ = std::make_unique<StepCache>(scene_, opt.backend, (uint64_t)opt.cache_mb << 20);
      swap_ = std::make_unique<SwapExchange>(ctx, maxPixelMessageBytes(scene_.width, scene_.height),
                                             2 * 16 * size_t(scene_.width) * size_t(scene_.height));
      bindSwap();
    }
  }

  // The swap socket is bound before Hello, which tells the master where it is (no rank is
  // needed for it). A renderer that cannot bind says so and gets direct-send frames only.
  void bindSwap() {
    std::string id;
    for (unsigned char c : link_.identity().substr(0, 8)) id += fmt::format("{:02x}", c);
    const std::string where = opt_.endpoints.swapBind(id);
    try {
      swap_->bind(where);
      swap_endpoint_ = opt_.endpoints.swapAdvertised(swap_->socket().get(zmq::sockopt::last_endpoint),
                                                     opt_.advertise_host);
      link_.setAdvertised(swap_endpoint_);
    } catch (const std::exception& e) {
      spdlog::warn("binary swap unavailable: cannot bind {} ({}); this renderer takes direct-send frames only "
                   "(set TESSERA_BIND_HOST to an address of this host)", where, e.what());
      swap_.reset();
    }
  }

  // A time series: what the step cache did over the run.
  void logSteps() {
    if (!steps_ || scene_.series.steps <= 1) return;
    const StepCacheStats s = steps_->take();
    spdlog::info("step cache: budget {} MiB, held at most {:.1f} MiB besides the shown step; {} hits, {} misses, {} bad steps",
                 opt_.cache_mb, (double)s.peak_bytes / (1 << 20), s.hits, s.misses, s.bad_steps);
  }

  int run(const std::atomic<bool>* stop) {
    stop_ = stop;
    if (!link_.join(stop)) {
      if (stop && *stop) return 0;  // stopped (Ctrl-C) while it waited: not a failure to join
      spdlog::error("renderer could not join the master at {}", opt_.endpoints.masterControl());
      return 1;
    }
    spdlog::info("renderer rank={} joined backend={} simd={}{}", link_.rank(),
                 scene_.mesh ? "osmesa-mesh" : backendName(opt_.backend), isaName(cpuIsa()),
                 swap_ ? " swap pieces at " + swap_endpoint_ : "");
    while (!stopped()) {
      pump(queued_.empty() ? 100 : 0);
      if (shutdown_) return 0;
      if (link_.masterLost()) return 1;
      std::erase_if(queued_, [&](const auto& p) { return !wanted(p); });
      if (queued_.empty()) continue;
      if (steps_) steps_->prefetch(stepsAfter(queued_));
      const proto::FrameParams p = std::move(queued_.front());
      queued_.pop_front();
      renderFrameOrLog(p);
    }
    return 0;
  }

 private:
  bool stopped() const { return shutdown_ || (stop_ && *stop_); }
  // Frames superseded by a newer epoch or cancelled by an interaction are skipped, not rendered.
  bool wanted(const proto::FrameParams& p) const { return p.epoch == epoch_ && p.frame >= first_wanted_; }

  // Waits up to `ms` for the master's messages and swap pieces, and takes what came: new
  // FrameParams are queued (drained before every frame, and while a swap waits), a Roster
  // admits peers, Shutdown ends the run.
  void pump(int ms) {
    zmq::pollitem_t items[] = {{link_.sub().handle(), 0, ZMQ_POLLIN, 0},
                               {link_.control().handle(), 0, ZMQ_POLLIN, 0},
                               {swap_ ? swap_->socket().handle() : nullptr, 0, ZMQ_POLLIN, 0}};
    pollFor(items, swap_ ? 3 : 2, std::chrono::milliseconds(ms));
    auto published = link_.receive(drops_);
    shutdown_ = shutdown_ || published.shutdown;
    for (auto& p : published.params) {
      epoch_ = std::max(epoch_, p.epoch);
      first_wanted_ = std::max(first_wanted_, p.first_wanted);
      queued_.push_back(std::move(p));
    }
    if (swap_) swap_->setWanted(epoch_, first_wanted_);
    if (items[1].revents & ZMQ_POLLIN)
      if (auto roster = link_.receiveRoster(drops_); roster && swap_) swap_->setRoster(*roster, drops_);
    if (swap_ && (items[2].revents & ZMQ_POLLIN)) swap_->receive(drops_);
  }

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
    st.role = proto::Role::Renderer, st.rank = link_.rank();
    st.frame = p.frame, st.epoch = p.epoch;
    if (const proto::SortFirstWork* work = p.sortFirst()) return renderTiles(p, *work, st);
    renderBricks(p, *p.sortLast(), st);
  }

  // The steps the frames after the first will show, soonest first, then the one the master
  // expects after the last: what to prefetch.
  static std::vector<int> stepsAfter(const std::deque<proto::FrameParams>& queued) {
    std::vector<int> steps;
    for (const auto& p : queued)
      for (int s : {(int)p.step, (int)p.next_step})
        if (s != (int)queued.front().step && std::find(steps.begin(), steps.end(), s) == steps.end()) steps.push_back(s);
    return steps;
  }

  void renderBricks(const proto::FrameParams& p, const proto::SortLastWork& work, proto::StageStats& st) {
    if (tiles_) return drops_.drop(~0u, "sort-last FrameParams for a geometry scene");
    if (!holdBricks(p, work, st)) return;
    closeSocketsNotIn(p, work);
    if (auto plan = planSwap(p, link_.rank())) {
      if (!swap_) return drops_.drop(~0u, "binary-swap FrameParams for a renderer without a swap socket");
      return swapBrick(p, *plan, st);
    }
    swap_rounds_logged_ = 0;  // direct send: say it when swapping starts again
    for (uint32_t b = 0; b < work.bricks.size(); ++b) {
      if (work.bricks[b].renderer != link_.rank()) continue;
      auto t0 = Clock::now();
      const Cached& c = render(p, work.bricks[b].brick, st);
      st.work_ms += msSince(t0);
      st.active = unite(st.active, c.active);
      st.active_pixels += c.active.area();
      auto t1 = Clock::now();
      for (const auto& region : p.regions) sendPiece(p, b, region, viewOf(c.image, c.active, region.region), st);
      st.encode_ms += msSince(t1);
    }
    st.dropped = drops_.total();
    link_.report(proto::encode(st, link_.rank()));
  }

  // Binary swap: this renderer's one brick, composited with the others' by swapping halves;
  // the finished band goes straight to the display as strips, as a compositor's region
  // would. A frame given up (a new epoch, a lost partner) reports nothing: the master issues
  // it again.
  void swapBrick(const proto::FrameParams& p, const SwapPlan& plan, proto::StageStats& st) {
    auto t0 = Clock::now();
    const Cached& c = render(p, p.sortLast()->bricks[plan.brick].brick, st);
    st.work_ms += msSince(t0);
    st.active = c.active, st.active_pixels = c.active.area();
    auto send = [&](const std::string& endpoint, std::vector<std::byte>&& bytes) { sendBytes(socketFor(endpoint), std::move(bytes)); };
    auto idle = [&](int ms, uint32_t partner) {
      link_.setWaiting(p.frame, partner);  // said in the heartbeats, for the master's blame
      pump(ms);
      return !stopped() && !link_.masterLost() && wanted(p);
    };
    if (plan.rounds.size() != swap_rounds_logged_) {  // said when the farm's shape changes
      swap_rounds_logged_ = plan.rounds.size();
      spdlog::info("frame={} binary swap among {} renderers: {} rounds, {}", p.frame, p.sortLast()->swap.size(),
                   plan.rounds.size(), plan.folded ? fmt::format("image folded into renderer {}'s", plan.rounds[0].partner)
                                                         : fmt::format("band rows [{}, {})", plan.band.y, plan.band.y + plan.band.h));
    }
    auto band = swap_->run(p, link_.rank(), plan, c.image, c.active, send, idle, st, drops_);
    link_.clearWaiting();
    if (!band) return spdlog::info("frame={} epoch={}: binary swap given up", p.frame, p.epoch);
    auto t1 = Clock::now();
    if (!plan.band.empty()) sendBand(p, *band, st);  // folded, or no rows: the display expects none (proto::swapBand)
    swap_->recycle(std::move(*band));
    st.encode_ms += msSince(t1);
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

  // Holds the voxels of this renderer's bricks and their ghost layer for the frame's step:
  // from the step cache, or loaded now. Memory follows the bricks, not the volume; a move
  // of bricks or a step not prefetched costs a load, in the stats. False: nothing to render
  // with (the step could not be read and no earlier step is held).
  bool holdBricks(const proto::FrameParams& p, const proto::SortLastWork& work, proto::StageStats& st) {
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
    if (need.lo[0] >= need.hi[0]) return true;  // no brick of ours this frame
    // Same window as before: keep the window held for it (bricks within the held window
    // after a neighbour's loss are rendered from it).
    if (held_.volume) {
      bool inside = true;
      for (int a = 0; a < 3; ++a)
        inside = inside && need.lo[a] >= held_.volume->origin[a] && need.hi[a] <= held_.volume->origin[a] + held_.volume->dims[a];
      if (inside) need = VoxelBox{held_.volume->origin, {held_.volume->origin[0] + held_.volume->dims[0],
                                                         held_.volume->origin[1] + held_.volume->dims[1],
                                                         held_.volume->origin[2] + held_.volume->dims[2]}};
      else held_ = {};  // before loading the next: peak memory is one window
    }
    held_ = steps_->get(need, (int)p.step);
    const StepCacheStats cs = steps_->take();
    st.load_ms = cs.load_ms;
    if (scene_.series.steps > 1) {
      st.step = (uint32_t)held_.step;
      st.step_hits = cs.hits;
      st.step_misses = cs.misses;
      st.bytes_read = cs.bytes_read;
      st.prefetch_ms = cs.prefetch_ms;
    }
    if (!held_.volume) throw std::runtime_error("step " + std::to_string(p.step) + " could not be read and no other step is held");
    if (cs.load_ms > 0)
      spdlog::info("frame={} step={} loaded voxels [{}, {}, {}] .. [{}, {}, {}) ({:.1f} MiB) in {:.0f} ms", p.frame, p.step,
                   need.lo[0], need.lo[1], need.lo[2], need.hi[0], need.hi[1], need.hi[2],
                   (double)held_.volume->voxelCount() * sizeof(float) / (1 << 20), cs.load_ms);
    return true;
  }

  struct Cached {
    RenderKey key;
    ImageF image;
    Rect active;
  };

  const Cached& render(const proto::FrameParams& p, const BrickBox& brick, proto::StageStats& st) {
    RenderKey key{p.camera, p.quality, p.width, p.height, brick, held_.step};
    for (auto& c : cache_)
      if (c.key == key) return ++st.images_reused, c;  // unchanged inputs: reuse, do not render again
    ++st.images_made;
    RenderOptions ro;
    ro.quality = p.quality;
    ro.threads = opt_.threads;
    Cached c{key, {}, {}};
    Brick local = brick;  // in the held window's voxel indices
    for (int a = 0; a < 3; ++a) local.lo[a] -= held_.volume->origin[a], local.hi[a] -= held_.volume->origin[a];
    // No RenderStats: the farm needs no sample counts, and counting skipped samples costs.
    ImageF spare;  // the oldest image's memory, so that a frame does not fault in fresh pages
    if (cache_.size() >= 2) {  // a renderer may own two bricks after a failure
      spare = std::move(cache_.front().image);
      cache_.pop_front();
    }
    c.image = held_.caster->render(p.camera, p.width, p.height, local, ro, nullptr, &c.active, std::move(spare));
    cache_.push_back(std::move(c));
    return cache_.back();
  }

  // `part`: the pixels of a brick image in the region, in the frame's format.
  void sendPiece(const proto::FrameParams& p, uint32_t brick, const proto::CompositorRegion& region,
                 const LayerView& part, proto::StageStats& st) {
    proto::Piece piece;
    piece.frame = p.frame;
    piece.epoch = p.epoch;
    piece.renderer = link_.rank();
    piece.brick = brick;
    piece.region = region.region;
    piece.active = part.rect;
    piece.format = p.format;
    piece.pixels = std::move(packed_);
    packView(part, p.format, piece.pixels);
    piece.render_ms = st.work_ms;
    auto bytes = proto::encode(piece, link_.rank(), p.codec);
    st.bytes_raw += piece.pixels.size();
    packed_ = std::move(piece.pixels);
    st.bytes_encoded += bytes.size();
    sendBytes(socketFor(region.endpoint), std::move(bytes));
  }

  // A finished band goes to the display as a compositor's region would.
  void sendBand(const proto::FrameParams& p, const Layer& band, proto::StageStats& st) {
    proto::Strips s;
    s.frame = p.frame;
    s.epoch = p.epoch;
    s.sender = link_.rank();
    bandStrips(band, p.width, p.height, band8_, s);
    s.render_ms = st.work_ms;
    s.composite_ms = st.decode_ms;  // the swap's decoding and blending
    auto bytes = proto::encode(s, link_.rank(), p.codec);
    st.bytes_raw += s.stream.size();
    st.bytes_encoded += bytes.size();
    sendBytes(socketFor(p.display_endpoint), std::move(bytes));
  }

  // Peers come and go (a restarted renderer has a new swap port): connections to endpoints
  // this frame does not name would retry a dead address forever.
  void closeSocketsNotIn(const proto::FrameParams& p, const proto::SortLastWork& work) {
    std::erase_if(pushes_, [&](const auto& kv) {
      const std::string& e = kv.first;
      return e != p.display_endpoint &&
             std::none_of(p.regions.begin(), p.regions.end(), [&](const auto& r) { return r.endpoint == e; }) &&
             std::none_of(work.swap.begin(), work.swap.end(), [&](const auto& s) { return s.endpoint == e; });
    });
  }

  zmq::socket_t& socketFor(const std::string& endpoint) {
    auto it = pushes_.find(endpoint);
    if (it == pushes_.end()) {
      zmq::socket_t s = makeSocket(ctx_, zmq::socket_type::dealer);
      s.set(zmq::sockopt::routing_id, link_.dataIdentity());  // compositors, partners and the display admit it by this
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
  std::unique_ptr<StepCache> steps_;  // volume scenes (sort-last): the windows of this renderer's bricks, per step
  HeldStep held_;                     // the window and caster of the frame being rendered
  std::unique_ptr<TileRenderer> tiles_;   // geometry scenes (sort-first)
  std::deque<Cached> cache_;
  std::vector<std::byte> packed_;  // a piece's pixels before encoding, kept (see packPixels)
  Image8 band8_;                   // a binary swap's band, quantized (the frame's size: strips name screen rows)
  std::map<std::string, zmq::socket_t> pushes_;  // to compositors, swap partners and the display
  std::unique_ptr<SwapExchange> swap_;  // volume scenes
  size_t swap_rounds_logged_ = 0;
  std::string swap_endpoint_;  // what Hello tells the master
  std::deque<proto::FrameParams> queued_;
  const std::atomic<bool>* stop_ = nullptr;
  bool shutdown_ = false;
  uint32_t epoch_ = 0;
  uint64_t first_wanted_ = 0;  // frames below it were cancelled
  uint64_t frames_failed_ = 0;
  DropCounter drops_;
};

}  // namespace

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  Stage s(opt, ctx);
  const int code = s.run(stop);
  s.logSteps();
  return code;
}

}  // namespace tessera::renderer
