#include "display/stage.h"

#include <chrono>
#include <deque>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "common/clock.h"
#include "common/net/curve.h"
#include "common/net/data_inbox.h"
#include "common/net/log.h"
#include "common/net/stage_link.h"
#include "common/wire/strips.h"
#include "common/net/transport.h"
#include "display/assembly.h"
#include "display/sink.h"

namespace tessera::display {
namespace {

class Stage {
 public:
  Stage(const StageOptions& opt, zmq::context_t& ctx)
      : opt_(opt), link_(ctx, opt.endpoints, proto::Role::Display, opt.scene),
        waiting_budget_(kWaitingFrames * 4 * size_t(opt.width + kStripHeaderPixels) * size_t(opt.height)),
        inbox_(ctx, {proto::Role::Compositor, proto::Role::Renderer}, maxPixelMessageBytes(opt.width, opt.height), waiting_budget_),
        frames_(waiting_budget_) {
    link_.expectFrameSize(opt.width, opt.height);
    inbox_.bind(opt_.endpoints.bind(opt_.endpoints.display()));
    // Listening from the start: a viewer may connect before the first frame.
    if (!opt_.web.empty()) web_ = makeWebSink(opt_.web, opt_.web_token, opt_.background.value_or(kWebBackground));
  }

  int run(const std::atomic<bool>* stop) {
    if (!link_.join(stop)) {
      if (stop && *stop) return 0;  // stopped (Ctrl-C) while it waited
      // The master cannot finish a run without the display: one that ended first failed (a
      // bad volume, say), and the display's exit is the farm's verdict (tessera-up's, and
      // `docker compose --exit-code-from display`'s). It exited 0: found by review.
      if (link_.runEnded()) {
        spdlog::error("the run ended before this display showed a frame (the master's reason is above)");
        return 1;
      }
      spdlog::error("display could not join the master at {}", opt_.endpoints.masterControl());
      return 1;
    }
    spdlog::info("display joined, strips at {}", opt_.endpoints.display());
    // Stages send strips where the display's address says, found from the master's host unless
    // TESSERA_DISPLAY_HOST names another: a display on a host of its own without it got
    // nothing, and the master blamed healthy renderers (found by review).
    if (!endpointIsHere(opt_.endpoints.display()))
      spdlog::warn("stages will send strips to {}, which is not an address of this host: set TESSERA_DISPLAY_HOST to "
                   "this host's name or address (the display's host, for every stage)", opt_.endpoints.display());
    zmq::pollitem_t items[] = {{link_.sub().handle(), 0, ZMQ_POLLIN, 0},
                               {link_.control().handle(), 0, ZMQ_POLLIN, 0},
                               {inbox_.socket().handle(), 0, ZMQ_POLLIN, 0}};
    while (!(stop && *stop)) {
      // A window that takes input is read every 4 ms. SDL stamps an event when it reads it, so
      // the wait for that read (<= 4 ms) is not in the input-to-present time.
      pollFor(items, 3, std::chrono::milliseconds(sink_ && sink_->interactive() ? 4 : 20));
      if ((items[0].revents & ZMQ_POLLIN) || link_.pending()) readParams();
      if (link_.masterLost()) return 1;
      // The roster before the strips: a new sender's first strips may wait for it.
      if (items[1].revents & ZMQ_POLLIN)
        if (auto roster = link_.receiveRoster(drops_)) readStrips(inbox_.setRoster(*roster, drops_));
      if (items[2].revents & ZMQ_POLLIN) readStrips(inbox_.receive(drops_));
      presentReady();
      if (auto a = frames_.awaited()) link_.setWaiting(a->first, a->second.rank);  // the master's blame
      else link_.clearWaiting();
      if (sink_ && pollInput()) return 0;
      if (shutdown_ && !frames_.nextHasParams()) break;  // strips without FrameParams never hold the display up
    }
    spdlog::info("display done: frames={} strips_rejected={} dropped={}", presented_, rejected_, drops_.total());
    return 0;
  }

 private:
  void readParams() {
    auto published = link_.receive(drops_);
    shutdown_ = shutdown_ || published.shutdown;
    for (auto& p : published.params) frames_.addParams(std::move(p));
    countLateDrops();
  }

  // Strips from roster members (compositors, and renderers with a binary swap's bands); the
  // sender they name must be the one their connection is.
  void readStrips(std::vector<DataInbox::Message> messages) {
    for (auto& [rank, m, role] : messages) {
      // At most a whole frame's pixels, each in a strip of its own: checked before decoding.
      auto s = proto::decodeStrips(view(m), maxStripStreamBytes(opt_.width, opt_.height));
      if (!s) {
        drops_.drop(rank, s.error());
        continue;
      }
      if (s->sender != rank) {
        drops_.drop(rank, fmt::format("claims {0} {1} from {0} {2}", proto::roleName(role), s->sender, rank));
        continue;
      }
      if (std::string why = frames_.addStrips({role, rank}, std::move(*s), m.size()); !why.empty()) drops_.drop(rank, why);
    }
    countLateDrops();
  }

  void countLateDrops() {
    for (const auto& [compositor, why] : frames_.takeLateDrops()) drops_.drop(compositor, why);
  }

  void presentReady() {
    while (auto f = frames_.popNext()) present(*f);
  }

  void present(Assembly::Frame& p) {
    const auto& params = *p.params;
    auto t0 = Clock::now();
    if (image_.width != params.width || image_.height != params.height) image_ = Image8(params.width, params.height);
    else std::fill(image_.px.begin(), image_.px.end(), 0);
    uint64_t rejected = 0;
    double render_ms = 0, composite_ms = 0;
    for (const auto& [source, s] : p.strips) {  // each within the part of the image it owns
      RouteStats rs = routeStrips(s.stream, image_, 0, Assembly::areaOf(params, source));
      rejected += rs.strips_rejected + (rs.truncated ? 1 : 0);
      render_ms = std::max(render_ms, s.render_ms);
      composite_ms = std::max(composite_ms, s.composite_ms);
    }
    if (rejected) spdlog::warn("frame={} strips_rejected={} (headers pointing outside the image or outside the part of it their sender owns, or corrupt)", params.frame, rejected);
    rejected_ += rejected;
    double route_ms = msSince(t0);
    openSink(params);
    fps_times_.push_back(Clock::now());
    while (fps_times_.size() > 1 && msSince(fps_times_.front()) > 2000) fps_times_.pop_front();
    double fps = fps_times_.size() > 1
                     ? (fps_times_.size() - 1) * 1000.0 /
                           std::chrono::duration<double, std::milli>(fps_times_.back() - fps_times_.front()).count()
                     : 0;
    std::string status = fmt::format("frame {}  {}  {:.1f} fps  latency {:.0f} ms  render {:.0f}  composite {:.1f}  display {:.1f} ms",
                                     params.frame, params.interactive ? fmt::format("moving: {}x{}", params.width, params.height)
                                                                      : std::string("sharp"),
                                     fps, msSince(p.first_seen), render_ms, composite_ms, last_display_ms_);
    if (opt_.steps > 1) status += fmt::format("  step {}/{}", params.step, opt_.steps - 1);
    if (!params.window.isDefault()) {  // the values the colour map spans (a generated volume's run 0..1)
      const auto r = link_.volumeRange();
      const auto v = windowRange(r[0] < r[1] ? r : std::array<double, 2>{0, 1}, params.window);
      status += fmt::format("  colours {:.5g}..{:.5g}", v[0], v[1]);  // 16-bit values in full
    }
    const auto input = inputShown(params);
    if (input) status += fmt::format("  input {:.0f} ms", msSince(input->at));  // up to now, before presenting
    if (sink_->interactive()) status += "  h: help";
    if (!params.interactive) full_size_ = {params.width, params.height};
    Shown shown{params.frame, status, params.interactive, full_size_[0], full_size_[1]};
    if (input) {
      shown.page = input->page;
      shown.page_input = input->page_input;
      shown.input_ms = msSince(input->at);
    }
    sink_->present(image_, shown);
    last_display_ms_ = msSince(t0);
    const double input_ms = input ? msSince(input->at) : 0;
    ++presented_;
    if (msSince(last_status_) > 1000) {
      spdlog::info("{}", status);
      last_status_ = Clock::now();
    }
    proto::FrameDone d;
    d.frame = params.frame;
    d.display_ms = last_display_ms_;
    d.route_ms = route_ms;
    d.bytes_encoded = p.bytes;
    d.strips_rejected = rejected_;
    d.dropped = drops_.total();
    d.input_ms = input_ms;
    link_.report(proto::encode(d, 0));
  }

  // When a frame is the first to show input: the time the first input it answers (the first
  // that changed the view after the frame before it was issued) reached the display.
  std::optional<InputEvent> inputShown(const proto::FrameParams& p) {
    if (p.input_seq <= shown_input_) return {};
    shown_input_ = p.input_seq;
    std::optional<InputEvent> first;
    if (auto it = inputs_.find(p.input_first); p.input_first && it != inputs_.end()) first = it->second;
    inputs_.erase(inputs_.begin(), inputs_.upper_bound(p.input_seq));
    return first;
  }

  void openSink(const proto::FrameParams& p) {
    if (sink_) return;
    using Window = StageOptions::Window;
    if (opt_.window != Window::Off) {
      try {
        sink_ = makeWindowSink(p.width, p.height, "Tessera");
      } catch (const std::runtime_error& e) {
        if (opt_.window == Window::On) throw;
        spdlog::info("no window ({}); writing PNG frames instead", e.what());
      }
    }
    if (sink_) {
      spdlog::info("display window {}x{}", p.width, p.height);
    } else {
      sink_ = makePngSink(opt_.out_dir, opt_.background, opt_.premultiplied);
      spdlog::info("display writing PNG frames to {}/", opt_.out_dir);
    }
    if (web_) {  // the web view first: it encodes on its own thread while the window draws
      std::vector<std::unique_ptr<Sink>> both;
      both.push_back(std::move(web_));
      both.push_back(std::move(sink_));
      sink_ = makeTeeSink(std::move(both));
    }
  }

  // True when the user quit.
  bool pollInput() {
    for (const auto& e : sink_->poll()) {
      if (e.quit) return true;
      proto::Input in;
      in.seq = ++input_seq_;
      in.orbit_dx = e.orbit_dx;
      in.orbit_dy = e.orbit_dy;
      in.zoom = e.zoom;
      in.quality = e.quality;
      in.interacting = e.interacting;
      in.width = e.width;
      in.height = e.height;
      in.time = e.time;
      in.home = e.home;
      in.window_shift = e.window_shift;
      in.window_scale = e.window_scale;
      inputs_[in.seq] = e;
      if (inputs_.size() > 4096) inputs_.erase(inputs_.begin());  // inputs no frame showed
      link_.report(proto::encode(in, 0));
    }
    return false;
  }

  const StageOptions& opt_;
  StageLink link_;
  size_t waiting_budget_;
  DataInbox inbox_;
  std::unique_ptr<Sink> sink_;
  std::unique_ptr<Sink> web_;  // the web view until the first frame joins it to sink_
  // The web view's background without --background: the window's dark grey.
  static constexpr std::array<double, 3> kWebBackground{32 / 255.0, 32 / 255.0, 36 / 255.0};
  // Strips waiting for FrameParams: at most this many whole frames of strips (every pixel
  // once at 4 bytes, plus 2 header pixels per row; a tiled frame's few headers more fit
  // in the slack); the race needs about one.
  static constexpr size_t kWaitingFrames = 8;
  Assembly frames_;
  uint64_t presented_ = 0, rejected_ = 0;
  uint64_t input_seq_ = 0, shown_input_ = 0;      // inputs sent; the newest one shown
  std::map<uint64_t, InputEvent> inputs_;  // inputs not shown yet (when they arrived, from which page)
  bool shutdown_ = false;
  Image8 image_;
  std::array<int, 2> full_size_{0, 0};  // the last full-quality frame's (a reduced frame is shown at it)
  std::deque<Clock::time_point> fps_times_;
  Clock::time_point last_status_{};
  double last_display_ms_ = 0;
  DropCounter drops_;
};

}  // namespace

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  Stage s(opt, ctx);
  return s.run(stop);
}

}  // namespace tessera::display
