#include "compositor/stage.h"

#include <chrono>
#include <cstring>
#include <map>
#include <utility>

#include "common/clock.h"
#include "common/net/curve.h"
#include "common/net/data_inbox.h"
#include "common/net/log.h"
#include "common/net/stage_link.h"
#include "common/wire/strips.h"
#include "common/net/transport.h"
#include "compositor/gather.h"
#include "compositor/over.h"

namespace tessera::compositor {
namespace {


class Stage {
 public:
  Stage(const StageOptions& opt, zmq::context_t& ctx)
      : opt_(opt), ctx_(ctx), link_(ctx, opt.endpoints, proto::Role::Compositor, opt.scene, opt.advertise_host),
        inbox_(ctx, {proto::Role::Renderer}, maxPixelMessageBytes(opt.width, opt.height),
               Gather::waitingBudget(opt.width, opt.height)),
        gather_(0) {
    link_.expectFrameSize(opt.width, opt.height);
    if (opt.maximum) mip_.emplace(*opt.maximum, opt.minimum);
  }

  int run(const std::atomic<bool>* stop) {
    if (!link_.join(stop)) {
      // Stopped (Ctrl-C) while it waited, or the run ended first: not a failure to join.
      if ((stop && *stop) || link_.runEnded()) return 0;
      spdlog::error("compositor could not join the master at {}", opt_.endpoints.masterControl());
      return 1;
    }
    uint32_t rank = link_.rank();
    gather_ = Gather(rank, Gather::waitingBudget(opt_.width, opt_.height));
    std::string bind = opt_.endpoints.compositorBind(rank);
    inbox_.bind(bind);
    spdlog::info("compositor rank={} joined, pieces at {}", rank, bind);
    // Without TESSERA_ADVERTISE_HOST peers reach a compositor at the master's host (found by
    // review: a compositor on another host then got nothing, and renderers were blamed).
    if (opt_.advertise_host.empty() && !endpointIsHere(opt_.endpoints.compositor(rank)))
      spdlog::warn("renderers will send pieces to {}, which is not an address of this host: set "
                   "TESSERA_ADVERTISE_HOST (ip, hostname, or this host's address)", opt_.endpoints.compositor(rank));
    zmq::pollitem_t items[] = {{link_.sub().handle(), 0, ZMQ_POLLIN, 0},
                               {link_.control().handle(), 0, ZMQ_POLLIN, 0},
                               {inbox_.socket().handle(), 0, ZMQ_POLLIN, 0}};
    while (!(stop && *stop)) {
      pollFor(items, 3, std::chrono::milliseconds(100));
      if (((items[0].revents & ZMQ_POLLIN) || link_.pending()) && !readParams()) return 0;
      if (link_.masterLost()) return 1;
      // The roster before the pieces: a new renderer's first pieces may wait for it.
      if (items[1].revents & ZMQ_POLLIN)
        if (auto roster = link_.receiveRoster(drops_)) accept(inbox_.setRoster(*roster, drops_));
      if (items[2].revents & ZMQ_POLLIN) accept(inbox_.receive(drops_));
      for (auto& why : gather_.takeLateDrops()) drops_.drop(~0u, why);
      while (auto ready = gather_.pop()) composite(*ready);
      if (auto a = gather_.awaited()) link_.setWaiting(a->first, a->second);  // the master's blame
      else link_.clearWaiting();
    }
    return 0;
  }

 private:
  // False on Shutdown.
  bool readParams() {
    auto published = link_.receive(drops_);
    for (auto& p : published.params)
      if (auto why = gather_.addParams(std::move(p)); !why.empty()) spdlog::debug("ignored FrameParams: {}", why);
    return !published.shutdown;
  }

  // Pieces (sort-last) or framebuffers (sort-first) from roster members; the renderer a
  // message names must be the one its connection belongs to.
  void accept(std::vector<DataInbox::Message> messages) {
    for (auto& [rank, m, role] : messages) {
      auto t0 = Clock::now();
      auto h = proto::decodeHeader(view(m));
      if (!h) {
        drops_.drop(rank, h.error());
        continue;
      }
      std::string why;
      auto claims = [&](uint32_t renderer) {
        return renderer == rank ? "" : "claims renderer " + std::to_string(renderer) + " from renderer " + std::to_string(rank);
      };
      if (h->type == proto::Type::Framebuffer) {
        auto fb = proto::decodeFramebuffer(view(m), largestPart());
        why = !fb ? fb.error() : claims(fb->renderer);
        if (why.empty()) why = gather_.addFramebuffer(std::move(*fb));
      } else {
        auto piece = proto::decodePiece(view(m), largestPart());
        why = !piece ? piece.error() : claims(piece->renderer);
        if (why.empty()) why = gather_.addPiece(std::move(*piece));
      }
      if (!why.empty()) {
        drops_.drop(rank, why);
        continue;
      }
      // Per frame: with frames in flight, parts of the next frames arrive between two
      // composites. Only accepted parts count, so the map is as bounded as the gather.
      decode_ms_[h->frame] += msSince(t0);
    }
  }

  // A part covers at most the whole image in the largest piece format (rgba32f).
  size_t largestPart() const { return 16 * (size_t)opt_.width * (size_t)opt_.height; }

  void composite(Gather::Ready& r) {
    proto::StageStats st;
    st.role = proto::Role::Compositor;
    st.rank = link_.rank();
    st.frame = r.params.frame;
    st.epoch = r.params.epoch;
    if (auto it = decode_ms_.find(st.frame); it != decode_ms_.end()) st.decode_ms = it->second;
    decode_ms_.erase(decode_ms_.begin(), decode_ms_.upper_bound(st.frame));
    if (!r.region) {  // no part in this frame (a binary swap's, or a spare compositor's)
      // In a binary-swap farm no compositor reports otherwise: its drops reach the metrics with
      // a report of its own. (In a direct-send frame one would stand in for the real ones.)
      if (!r.params.regions.empty() || dropped() == reported_drops_) return;
      st.dropped = reported_drops_ = dropped();
      return link_.report(proto::encode(st, link_.rank()));
    }
    auto t0 = Clock::now();
    const Rect& reg = *r.region;
    if (frame_.width != r.params.width || frame_.height != r.params.height)
      frame_ = Image8(r.params.width, r.params.height);
    const proto::SortLastWork* sort_last = r.params.sortLast();  // else sort-first: r.tiles are routed
    if (sort_last) st.active_pixels = compositeRegion(reg, sort_last->order, r.pieces, row_, frame_,
                                                          mip_ ? &mip_->at(r.params.window) : nullptr);
    else route(r, st);
    st.work_ms = msSince(t0);
    for (const auto& p : r.pieces) st.active = unite(st.active, p.active);
    auto t1 = Clock::now();
    proto::Strips s;
    s.frame = r.params.frame;
    s.epoch = r.params.epoch;
    s.sender = link_.rank();
    if (sort_last) {
      s.stream = encodeStrips(frame_, reg, 0);
    } else {
      for (const Rect& t : r.tiles) {
        auto part = encodeStrips(frame_, t, 0);
        s.stream.insert(s.stream.end(), part.begin(), part.end());
      }
    }
    s.composite_ms = st.work_ms;
    s.active_pixels = st.active_pixels;
    for (const auto& p : r.pieces) s.render_ms = std::max(s.render_ms, p.render_ms);
    auto bytes = proto::encode(s, link_.rank(), r.params.codec);
    s.encode_ms = msSince(t1);
    st.encode_ms = s.encode_ms;
    st.bytes_raw = s.stream.size();
    st.bytes_encoded = bytes.size();
    if (!sendBytes(display(r.params.display_endpoint), std::move(bytes)))  // the display stopped reading
      unsent_.drop(0, fmt::format("strips not sent to the display: the queue to it stayed full for {} ms",
                                  kDataSendTimeout.count()));
    st.dropped = reported_drops_ = dropped();
    link_.report(proto::encode(st, link_.rank()));
  }

  // Sort-first: strips find their place from their headers alone (Lightning-2 style), each
  // renderer's into its own tiles. The tiles are cleared first, so a
  // row a renderer left out is transparent, never the frame before's.
  void route(const Gather::Ready& r, proto::StageStats& st) {
    for (const Rect& t : r.tiles) frame_.clear(t);
    std::vector<Rect> own;
    for (const auto& fb : r.framebuffers) {
      own.clear();
      for (const auto& t : r.params.sortFirst()->tiles)  // never none: Gather::check admits no other renderer
        if (t.compositor == link_.rank() && t.renderer == fb.renderer) own.push_back(t.tile);
      Image8 img(fb.width, fb.height);
      std::memcpy(img.px.data(), fb.pixels.data(), fb.pixels.size());
      RouteStats rs = routeFramebuffer(img, frame_, 0, own);
      if (rs.strips_rejected) drops_.drop(fb.renderer, std::to_string(rs.strips_rejected) + " strips rejected");
      st.active_pixels += rs.pixels_written;
    }
  }

  zmq::socket_t& display(const std::string& endpoint) {
    if (endpoint != display_endpoint_) {
      display_ = connectDataSender(ctx_, endpoint, link_.dataIdentity());
      display_endpoint_ = endpoint;
    }
    return display_;
  }

  const StageOptions& opt_;
  zmq::context_t& ctx_;
  StageLink link_;
  DataInbox inbox_;
  zmq::socket_t display_;
  std::string display_endpoint_;
  Gather gather_;
  std::vector<float> row_;
  Image8 frame_;
  std::optional<WindowedMaxIntensity> mip_;  // blend: maximum or minimum
  std::map<uint64_t, double> decode_ms_;  // by frame
  DropCounter drops_;
  DropCounter unsent_;  // strips this compositor could not send (apart: drops_ counts by sender)
  uint64_t dropped() const { return drops_.total() + unsent_.total(); }  // what Stats report
  uint64_t reported_drops_ = 0;
};

}  // namespace

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  Stage s(opt, ctx);
  return s.run(stop);
}

}  // namespace tessera::compositor
