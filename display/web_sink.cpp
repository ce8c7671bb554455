// The web view as a display sink: frames are encoded on the sink's own thread (the newest
// wins, so encoding never holds the display loop up), and only while someone watches, and
// handed to the server; viewers' input becomes the same InputEvents the window makes.
#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <spdlog/spdlog.h>

#include "display/sink.h"
#include "display/web_server.h"

namespace tessera::display {
namespace {

// JPEG quality of the frames while the camera moves (see the README's web view figures).
constexpr int kJpegQuality = 90;

class WebSink final : public Sink {
 public:
  WebSink(const std::string& address, const std::string& token, const std::array<double, 3>& background)
      : server_(address, token), background_(background) {
    spdlog::info("web view: open {}", server_.url());
    // A viewer that connects gets the newest frame encoded now (none are while nobody watches).
    server_.onViewer([this] {
      {
        std::lock_guard lock(m_);
        if (!next_ && last_) next_ = last_;
        joined_ = true;  // present() may have counted no viewers just before this one came
      }
      cv_.notify_one();
    });
    encoder_ = std::thread([this] { encodeLoop(); });
  }

  ~WebSink() override {
    server_.onViewer({});  // under the server's lock: no viewer callback reaches this sink after it
    {
      std::lock_guard lock(m_);
      quit_ = true;
    }
    cv_.notify_one();
    encoder_.join();
    WebCounters c = server_.counters();
    spdlog::info("web view: {} connections, {} frames sent, {} replaced before sending, {} refused, "
                 "{} bad messages, {} bad requests",
                 c.connections, c.frames_sent, c.frames_replaced, c.refused, c.bad_messages, c.bad_requests);
    if (c.cut_short) spdlog::info("web view: {} viewers closed in the middle of a frame (stopped reading, or left)", c.cut_short);
    for (auto [kind, ms] : {std::pair{"lossless", &c.lossless_ms}, std::pair{"moving", &c.moving_ms}}) {
      if (ms->empty()) continue;
      std::sort(ms->begin(), ms->end());
      spdlog::info("web view: {} frames on the page {:.0f} ms (median), {:.0f} ms (max) after the display presented "
                   "them ({} frames)", kind, (*ms)[(ms->size() - 1) / 2], ms->back(), ms->size());
    }
  }

  // Lock order: the server's mutex (its viewer callback) before m_; never the reverse.
  void present(const Image8& frame, const Shown& shown) override {
    const bool watched = server_.viewers() > 0;
    {
      std::lock_guard lock(m_);
      last_ = Next{frame, shown, std::chrono::steady_clock::now()};
      if (watched || joined_) next_ = last_;
      joined_ = false;
    }
    cv_.notify_one();
  }

  std::vector<InputEvent> poll() override {
    std::vector<InputEvent> out;
    for (const auto& in : server_.takeInput()) {
      InputEvent ev;
      ev.at = in.at;
      ev.page = in.page;
      ev.page_input = in.n;
      if (!translate(in.msg, ev)) continue;
      // Consecutive drags collapse into one, as the window's do: the master needs the sum.
      if (!out.empty() && addDrag(out.back(), ev)) continue;
      out.push_back(ev);
    }
    return out;
  }

  bool interactive() const override { return true; }

 private:
  struct Next {
    Image8 frame;
    Shown shown;
    std::chrono::steady_clock::time_point at;  // presented
  };

  void encodeLoop() {
    std::unique_lock lock(m_);
    while (true) {
      cv_.wait(lock, [&] { return quit_ || next_; });
      if (quit_) return;
      Next n = std::move(*next_);
      next_.reset();
      lock.unlock();
      try {
        auto f = std::make_shared<WebFrame>(encodeWebFrame(n.frame, n.shown, background_, kJpegQuality));
        f->shown_at = n.at;
        server_.publish(std::move(f));
      } catch (const std::exception& e) {
        spdlog::warn("web view: frame {} not sent: {}", n.shown.id, e.what());
      }
      lock.lock();
    }
  }

  // A viewer's message (checked by the server) as the window's input; false if it is none.
  static bool translate(const nlohmann::json& msg, InputEvent& ev) {
    const std::string t = msg["t"].get<std::string>();
    if (t == "drag" || t == "window") {  // the left or right button's
      ev = dragEvent(ev, msg["dx"].get<double>(), msg["dy"].get<double>(), t == "window");
    } else if (t == "wheel") {
      ev.zoom = std::pow(kZoomPerNotch, msg["notches"].get<double>());
      ev.interacting = true;
    } else if (t == "key") {
      const std::string key = msg["key"].get<std::string>();
      if (key == "1") ev.quality = QualityName::Reference;
      else if (key == "2") ev.quality = QualityName::Default;
      else if (key == "3") ev.quality = QualityName::Fast;
      else if (key == " ") ev.time = proto::TimeKey::PlayPause;
      else if (key == "ArrowRight") ev.time = proto::TimeKey::Forward;
      else if (key == "ArrowLeft") ev.time = proto::TimeKey::Back;
      else if (key == "Home") ev.time = proto::TimeKey::First;
      else if (key == "End") ev.time = proto::TimeKey::Last;
      else if (key == "r") ev.home = true;
      else return false;
    }  // "release": interacting = false, the full frame now
    return true;
  }

  WebServer server_;
  std::array<double, 3> background_;
  std::mutex m_;
  std::condition_variable cv_;
  std::optional<Next> next_, last_;  // to encode; the newest presented
  bool quit_ = false;
  bool joined_ = false;  // a viewer connected since the last present()
  std::thread encoder_;
};

}  // namespace

std::unique_ptr<Sink> makeWebSink(const std::string& address, const std::string& token,
                                  const std::array<double, 3>& background) {
  return std::make_unique<WebSink>(address, token, background);
}

}  // namespace tessera::display
