#include "renderer/stage.h"

#include <chrono>
#include <deque>
#include <optional>

#include "common/clock.h"
#include "common/cpu.h"
#include "common/volume_summary.h"
#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/wire/pixels.h"
#include "common/wire/protocol.h"
#include "common/net/stage_link.h"
#include "common/net/transport.h"
#include "renderer/brick_images.h"
#include "renderer/outbox.h"
#include "renderer/render_worker.h"
#include "renderer/swap_exchange.h"
#include "renderer/tile_render.h"

namespace tessera::renderer {
namespace {

class Stage {
 public:
  Stage(const StageOptions& opt, zmq::context_t& ctx)
      : opt_(opt), ctx_(ctx), link_(ctx, opt.endpoints, proto::Role::Renderer, sceneIdentity(opt.scene)), scene_(opt.scene) {
    link_.expectFrameSize(scene_.width, scene_.height);
    if (opt.scene.mesh) {
      tiles_ = std::make_unique<TileRenderer>(opt.scene);
    } else {
      // Every window is normalised with the whole file's range (a series: step 0's): the
      // master's, which comes with its Welcome (see fixRange).
      images_ = std::make_unique<BrickImages>(scene_, opt.backend, opt.cache_mb, opt.threads);
      swap_ = std::make_unique<SwapExchange>(ctx, maxPixelMessageBytes(scene_.width, scene_.height),
                                             2 * 16 * size_t(scene_.width) * size_t(scene_.height));
      swap_->setMaximum(isProjection(scene_.blend));
      // Seen through each frame's window.
      if (isProjection(scene_.blend)) mip_.emplace(scene_.tf, scene_.blend == Blend::Minimum);
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
      spdlog::warn("binary swap unavailable: {}; this renderer takes direct-send frames only", e.what());
      swap_.reset();
    }
  }

  // A volume file without `range` is normalised with the range the master streamed the file
  // for, so this renderer reads only its bricks (#9: never the whole volume); a master that
  // sent none leaves the scan to this renderer. Before the first frame: nothing loaded yet.
  void fixRange() {
    auto* raw = std::get_if<RawVolumeSpec>(&scene_.volume);
    if (!images_ || !raw || raw->has_range) return;
    const auto r = link_.volumeRange();
    if (r[0] < r[1]) raw->has_range = true, raw->range = r;
    else fixVolumeRange(scene_);
  }

  void logSteps() {
    if (images_) images_->logSteps();
    if (std::holds_alternative<RawVolumeSpec>(scene_.volume))
      spdlog::info("read {:.1f} MiB of volume samples{}", (double)volumeSamplesRead() / (1 << 20),
                   volumeBytesInflated() ? fmt::format(" ({:.2f} MiB decompressed)", (double)volumeBytesInflated() / (1 << 20)) : "");
  }

  int run(const std::atomic<bool>* stop) {
    stop_ = stop;
    if (!link_.join(stop)) {
      // Stopped (Ctrl-C) while it waited, or the run ended first: not a failure to join.
      if ((stop && *stop) || link_.runEnded()) return 0;
      spdlog::error("renderer could not join the master at {}", opt_.endpoints.masterControl());
      return 1;
    }
    fixRange();
    spdlog::info("renderer rank={} joined backend={} simd={} gather={}{}", link_.rank(),
                 scene_.mesh ? "osmesa-mesh" : backendName(opt_.backend), isaName(cpuIsa()), gathersName(cpuGathers()),
                 swap_ ? " swap pieces at " + swap_endpoint_ : "");
    while (!stopped()) {
      const bool ready = !queued_.empty() && canStart(queued_.front());
      // Nothing to render while a frame's rounds await a partner's piece: that idle time is
      // the frame's wait (the metrics' render_swap_wait_ms_max).
      const bool idle_in_rounds = swapping_ && !worker_.busy() && !ready;
      const double polled_ms = pump(ready ? 0 : worker_.busy() || swapping_ ? 50 : 100);
      if (idle_in_rounds) swapping_->st.wait_ms += polled_ms;
      if (shutdown_) return 0;
      if (link_.masterLost()) return 1;
      std::erase_if(queued_, [&](const auto& p) { return !wanted(p); });
      collectRender();
      advanceRounds();
      if (queued_.empty() || !canStart(queued_.front())) continue;
      if (images_) images_->prefetch(queued_);
      const proto::FrameParams p = std::move(queued_.front());
      queued_.pop_front();
      renderFrameOrLog(p);
    }
    return 0;
  }

 private:
  // A binary-swap frame: rendered (on the worker), then its rounds played.
  struct SwapFrame {
    proto::FrameParams p;
    proto::StageStats st;
    SwapPlan plan;
    const BrickImages::Image* c = nullptr;  // in images_
    std::string error;                      // the render threw
  };

  bool stopped() const { return shutdown_ || (stop_ && *stop_); }
  // Frames superseded by a newer epoch or cancelled by an interaction are skipped, not rendered.
  bool wanted(const proto::FrameParams& p) const { return p.epoch == epoch_ && p.frame >= first_wanted_; }

  // A binary-swap frame renders on the worker while the rounds of the one before it advance
  // here; every other frame renders on this thread once both are over (they are rare beside
  // swapping: direct send, a lost renderer's extra bricks, sort-first).
  bool canStart(const proto::FrameParams& p) const {
    if (worker_.busy() || rendering_) return false;
    const proto::SortLastWork* work = p.sortLast();
    const bool swapping = swap_ && !tiles_ && work && planSwap(p, link_.rank());
    return swapping || !swapping_;
  }

  // Waits up to `ms` for the master's messages and swap pieces, and takes what came: new
  // FrameParams are queued (between renders and while the worker renders), a Roster
  // admits peers, Shutdown ends the run. Returns the time it waited for them.
  double pump(int ms) {
    zmq::pollitem_t items[] = {{link_.sub().handle(), 0, ZMQ_POLLIN, 0},
                               {link_.control().handle(), 0, ZMQ_POLLIN, 0},
                               {nullptr, worker_.fd(), ZMQ_POLLIN, 0},  // a render ended
                               {swap_ ? swap_->socket().handle() : nullptr, 0, ZMQ_POLLIN, 0}};
    const auto t0 = Clock::now();
    pollFor(items, swap_ ? 4 : 3, std::chrono::milliseconds(ms));
    const double polled_ms = msSince(t0);
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
    if (swap_ && (items[3].revents & ZMQ_POLLIN)) swap_->receive(drops_);
    return polled_ms;
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

  void renderBricks(const proto::FrameParams& p, const proto::SortLastWork& work, proto::StageStats& st) {
    if (tiles_) return drops_.drop(~0u, "sort-last FrameParams for a geometry scene");
    outbox_.keepOnly(p, work);
    const uint32_t rank = link_.rank();
    if (auto plan = planSwap(p, rank)) {
      if (!swap_) return drops_.drop(~0u, "binary-swap FrameParams for a renderer without a swap socket");
      return renderForSwap(p, *plan, st);
    }
    swap_size_logged_ = 0;  // direct send: say it when swapping starts again
    worker_.runAndWait([&] { images_->hold(p, work, rank, st); });
    for (uint32_t b = 0; b < work.bricks.size(); ++b) {
      if (work.bricks[b].renderer != rank) continue;
      auto t0 = Clock::now();
      const BrickImages::Image* rendered = nullptr;
      worker_.runAndWait([&] { rendered = &images_->render(p, work.bricks[b].brick, st, nullptr); });
      const BrickImages::Image& c = *rendered;
      st.work_ms += msSince(t0);
      st.active = unite(st.active, c.active);
      st.active_pixels += c.active.area();
      auto t1 = Clock::now();
      for (const auto& region : p.regions) sendPiece(p, b, region, viewOf(c.image, c.active, region.region), st);
      st.encode_ms += msSince(t1);
    }
    st.dropped = dropped();
    link_.report(proto::encode(st, link_.rank()));
  }

  // Binary swap: this renderer's one brick, loaded if need be and rendered on the worker,
  // then composited with the others' by swapping halves (advanceRounds); the finished band
  // goes straight to the display as strips, as a compositor's region would.
  void renderForSwap(const proto::FrameParams& p, const SwapPlan& plan, const proto::StageStats& st) {
    rendering_ = SwapFrame{p, st, plan, nullptr, {}};
    const BrickBox brick = p.sortLast()->bricks[plan.brick].brick;
    const BrickImages::Image* in_rounds = swapping_ ? swapping_->c : nullptr;  // its image must outlive this render
    worker_.start([this, brick, in_rounds, rank = link_.rank()] {
      SwapFrame& f = *rendering_;  // this thread's alone until takeDone()
      try {
        images_->hold(f.p, *f.p.sortLast(), rank, f.st);
        auto t0 = Clock::now();
        f.c = &images_->render(f.p, brick, f.st, in_rounds);
        f.st.work_ms += msSince(t0);
      } catch (const std::exception& e) {
        f.error = e.what();
      } catch (...) {
        f.error = "unknown exception";
      }
    });
  }

  // A render the worker ended: its frame's rounds start as soon as the previous frame's end.
  void collectRender() {
    if (!worker_.takeDone()) return;
    if (!rendering_->error.empty()) {
      ++frames_failed_;
      spdlog::error("frame={} render failed: {} frames_failed={}", rendering_->p.frame, rendering_->error, frames_failed_);
      rendering_.reset();
    }
  }

  // Plays the rounds the partners' pieces allow, never waiting, for the frame in its rounds
  // and then for the rendered one after it. A frame given up (a new epoch, a lost partner, a
  // cancel) reports nothing: the master issues it again. A frame whose rounds throw costs
  // that frame, as a render that throws does.
  void advanceRounds() {
    while (swapping_ || (rendering_ && !worker_.busy())) {
      if (!swapping_) {
        swapping_ = std::move(rendering_);
        rendering_.reset();
      }
      try {
        if (!playRounds(*swapping_)) return;  // a partner's piece is awaited
      } catch (const std::exception& e) {
        swap_->abandon();
        link_.clearWaiting();
        ++frames_failed_;
        spdlog::error("frame={} binary swap failed: {} frames_failed={}", swapping_->p.frame, e.what(), frames_failed_);
      }
      swapping_.reset();
    }
  }

  // True when the frame is over: its band sent and its stats reported, or given up.
  bool playRounds(SwapFrame& f) {
    if (stopped() || link_.masterLost() || !wanted(f.p)) {
      swap_->abandon();
      link_.clearWaiting();
      spdlog::info("frame={} epoch={}: binary swap given up", f.p.frame, f.p.epoch);
      return true;
    }
    if (!swap_->running()) {  // its rounds begin
      f.st.active = f.c->active, f.st.active_pixels = f.c->active.area();
      if (f.p.sortLast()->swap.size() != swap_size_logged_) {  // said when the farm's shape changes
        swap_size_logged_ = f.p.sortLast()->swap.size();
        spdlog::info("frame={} binary swap among {} renderers: {} rounds, band rows [{}, {})", f.p.frame,
                     f.p.sortLast()->swap.size(), f.plan.rounds.size(), f.plan.band.y, f.plan.band.y + f.plan.band.h);
      }
      swap_->start(f.p, link_.rank(), f.plan, f.c->image, f.c->active);
    }
    auto send = [&](const std::string& endpoint, std::vector<std::byte>&& bytes) { sendTo(endpoint, std::move(bytes)); };
    if (const auto partner = swap_->advance(send, f.st, drops_)) {
      link_.setWaiting(f.p.frame, *partner);  // said in the heartbeats, for the master's blame
      return false;
    }
    link_.clearWaiting();
    Layer band = swap_->finish();
    auto t1 = Clock::now();
    if (!f.plan.band.empty()) sendBand(f.p, band, f.st);  // no rows: the display expects none (proto::swapBand)
    swap_->recycle(std::move(band));
    f.st.encode_ms += msSince(t1);
    f.st.dropped = dropped();
    link_.report(proto::encode(f.st, link_.rank()));
    return true;
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
      sendTo(*endpoint, std::move(bytes));
    }
    st.encode_ms = msSince(t0);
    st.dropped = dropped();
    link_.report(proto::encode(st, link_.rank()));
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
    sendTo(region.endpoint, std::move(bytes));
  }

  // A finished band goes to the display as a compositor's region would.
  void sendBand(const proto::FrameParams& p, Layer& band, proto::StageStats& st) {
    proto::Strips s;
    s.frame = p.frame;
    s.epoch = p.epoch;
    s.sender = link_.rank();
    bandStrips(band, p.width, p.height, band8_, s, mip_ ? &mip_->at(p.window) : nullptr);
    s.render_ms = st.work_ms;
    s.composite_ms = st.decode_ms;  // the swap's decoding and blending
    auto bytes = proto::encode(s, link_.rank(), p.codec);
    st.bytes_raw += s.stream.size();
    st.bytes_encoded += bytes.size();
    sendTo(p.display_endpoint, std::move(bytes));
  }

  void sendTo(const std::string& endpoint, std::vector<std::byte>&& bytes) { outbox_.send(endpoint, std::move(bytes)); }

  const StageOptions& opt_;
  zmq::context_t& ctx_;
  StageLink link_;
  Scene scene_;                      // the scene, with the data's range fixed once
  std::unique_ptr<BrickImages> images_;  // volume scenes (sort-last)
  std::unique_ptr<TileRenderer> tiles_;   // geometry scenes (sort-first)
  std::vector<std::byte> packed_;  // a piece's pixels before encoding, kept (see packPixels)
  Image8 band8_;                   // a binary swap's band, quantized (the frame's size: strips name screen rows)
  Outbox outbox_{ctx_, link_.dataIdentity()};  // to compositors, swap partners and the display
  std::unique_ptr<SwapExchange> swap_;  // volume scenes
  std::optional<WindowedMaxIntensity> mip_;  // blend: maximum or minimum: maps the bands this renderer finishes
  size_t swap_size_logged_ = 0;  // renderers in the swap, when last said
  std::string swap_endpoint_;  // what Hello tells the master
  std::deque<proto::FrameParams> queued_;
  const std::atomic<bool>* stop_ = nullptr;
  bool shutdown_ = false;
  uint32_t epoch_ = 0;
  uint64_t first_wanted_ = 0;  // frames below it were cancelled
  uint64_t frames_failed_ = 0;
  DropCounter drops_;
  uint64_t dropped() const { return drops_.total() + outbox_.unsent(); }  // what Stats report
  std::optional<SwapFrame> rendering_;  // on the worker, or rendered and waiting for the rounds before it
  std::optional<SwapFrame> swapping_;   // its rounds in progress (swap_)
  RenderWorker worker_;  // last: destroyed first, after its job, while what the job uses lives
};

}  // namespace

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  // Before it joins: a farm would wait for a renderer that fails every frame.
  if (std::string why = backendProblem(opt.backend, opt.scene.shading, opt.scene.blend); !why.empty()) {
    spdlog::error("{}", why);
    return 1;
  }
  Stage s(opt, ctx);
  const int code = s.run(stop);
  s.logSteps();
  return code;
}

}  // namespace tessera::renderer
