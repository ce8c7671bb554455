// SDL2 window sink: premultiplied frames scaled to fit the window (bilinear, centred) and
// composited over a dark background, a status strip and an optional help overlay drawn at the
// window's own resolution with the built-in font, and mouse/keyboard/resize input translated
// to InputEvents.
#include <SDL.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "common/resample.h"
#include "display/font.h"
#include "display/sink.h"

namespace tessera::display {
namespace {

constexpr uint8_t kBackground[3] = {32, 32, 36};  // a window has no alpha: show over dark grey
constexpr uint8_t kStripDim = 96;  // strip pixels keep 96/256 of their colour behind the text
constexpr std::array<uint8_t, 4> kTextColor = {230, 230, 230, 255};
constexpr const char* kHelp[] = {
    "drag: orbit    wheel: zoom    resize: re-render at the window's size",
    // Double spaces are where a narrow window breaks a line (wrap).
    "right drag: colour window  (right/left: wider/narrower,  up/down: higher/lower level)",
    "while the mouse moves the farm shows reduced frames,  then the full one",
    "1 / 2 / 3: reference / default / fast quality    r: the scene's view and colours again",
    "a time series: Space play/pause   <- -> step back/forward   Home/End first/last step",
    "h: this help    Esc, q or closing the window: stop the farm",
};

// Premultiplied over an opaque background: out = c + (1 - a) * bg. term[ch][a] holds the
// rounded second term, so each channel costs one table look-up and one add.
struct BackgroundTable {
  uint8_t term[3][256];
  BackgroundTable() {
    for (int ch = 0; ch < 3; ++ch)
      for (int a = 0; a < 256; ++a) term[ch][a] = (uint8_t)((kBackground[ch] * (255 - a) + 127) / 255);
  }
};

std::runtime_error sdlError(const std::string& what) {
  return std::runtime_error("display window: " + what + ": " + SDL_GetError());
}

// Starts SDL video on a real display server, or returns why not. When DISPLAY names a server
// that does not answer (yet), SDL quietly falls back to its offscreen driver and every frame
// goes nowhere: a window nobody can see must be an error, not a success.
std::string initVideo() {
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  // Nothing to try (and SDL's Wayland probe would print an XDG_RUNTIME_DIR error on headless hosts).
  if ((!x11 || !*x11) && (!wayland || !*wayland)) return "neither DISPLAY nor WAYLAND_DISPLAY is set";
  SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");  // the stage owns SIGINT/SIGTERM, not SDL
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0)
    return std::string("SDL_Init(VIDEO) failed: ") + SDL_GetError();
  const std::string driver = SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : "";
  if (driver == "x11" || driver == "wayland") return "";
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
  return "no X11 or Wayland server answered (DISPLAY=" + std::string(x11 ? x11 : "") +
         "); SDL offered only its '" + driver + "' driver, which shows nothing";
}

class WindowSink final : public Sink {
 public:
  WindowSink(int width, int height, const std::string& title) {
    if (width <= 0 || height <= 0)
      throw std::invalid_argument("display window: size must be positive, got " +
                                  std::to_string(width) + "x" + std::to_string(height));
    if (const std::string why = initVideo(); !why.empty())
      throw std::runtime_error("display window: " + why);
    window_ = SDL_CreateWindow(title.c_str(), SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED,
                               width, height, SDL_WINDOW_SHOWN | SDL_WINDOW_RESIZABLE);
    if (!window_) {
      auto err = sdlError("SDL_CreateWindow failed");
      SDL_QuitSubSystem(SDL_INIT_VIDEO);
      throw err;
    }
    // No vsync: the farm's pipeline, not the monitor, should pace frames.
    renderer_ = SDL_CreateRenderer(window_, -1, 0);
    if (!renderer_) {
      auto err = sdlError("SDL_CreateRenderer failed");
      SDL_DestroyWindow(window_);
      SDL_QuitSubSystem(SDL_INIT_VIDEO);
      throw err;
    }
    SDL_RendererInfo info{};
    SDL_GetRendererInfo(renderer_, &info);
    spdlog::info("window open size={}x{} video={} renderer={}", width, height,
                 SDL_GetCurrentVideoDriver(), info.name ? info.name : "?");
  }

  ~WindowSink() override {
    if (texture_) SDL_DestroyTexture(texture_);
    SDL_DestroyRenderer(renderer_);
    SDL_DestroyWindow(window_);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
  }

  WindowSink(const WindowSink&) = delete;
  WindowSink& operator=(const WindowSink&) = delete;

  void present(const Image8& frame, const Shown& shown) override {
    if (frame.width <= 0 || frame.height <= 0) return;
    if (frame.px.size() != (size_t)frame.width * frame.height * 4)
      throw std::invalid_argument("display window: frame pixel buffer has the wrong size");
    frame_ = frame;  // kept to draw again after a resize, an expose or the help key
    status_ = shown.status;
    draw();
  }

  bool interactive() const override { return true; }

  std::vector<InputEvent> poll() override {
    std::vector<InputEvent> out;
    SDL_Event e;
    // Bounded by what is queued now; events that arrive meanwhile wait for the next call.
    for (int n = 0; n < 4096 && SDL_PollEvent(&e); ++n) translate(e, out);
    return out;
  }

 private:
  // The frame scaled to fit the window (same shape, centred), the status strip and the help.
  void draw() {
    if (frame_.width <= 0) return;
    int ww = 0, wh = 0;
    SDL_GetRendererOutputSize(renderer_, &ww, &wh);
    if (ww <= 0 || wh <= 0) return;
    ensureTexture(ww, wh);
    const double s = std::min((double)ww / frame_.width, (double)wh / frame_.height);
    const int dw = std::clamp((int)std::lround(frame_.width * s), 1, ww);
    const int dh = std::clamp((int)std::lround(frame_.height * s), 1, wh);
    const bool same = dw == frame_.width && dh == frame_.height;
    const Image8 scaled = same ? Image8() : resizeBilinear(frame_, dw, dh);
    composite(same ? frame_ : scaled, (ww - dw) / 2, (wh - dh) / 2);
    const int scale = ww >= 800 ? 2 : 1;
    drawLines(wrap(status_, ww, scale), scale, false);
    if (help_) {  // wrapped as the status line is (it was cut at the window's edge: found by review)
      std::vector<std::string> help;
      for (const char* line : kHelp)
        for (std::string& part : wrap(line, ww, scale)) help.push_back(std::move(part));
      drawLines(help, scale, true);
    }
    if (SDL_UpdateTexture(texture_, nullptr, buffer_.px.data(), buffer_.width * 4) != 0)
      throw sdlError("SDL_UpdateTexture failed");
    SDL_RenderClear(renderer_);
    SDL_RenderCopy(renderer_, texture_, nullptr, nullptr);
    SDL_RenderPresent(renderer_);
  }

  void ensureTexture(int w, int h) {
    if (texture_ && w == buffer_.width && h == buffer_.height) return;
    if (texture_) SDL_DestroyTexture(texture_);
    // RGBA32 is R,G,B,A in memory on any endianness, matching Image8's byte order.
    texture_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGBA32, SDL_TEXTUREACCESS_STREAMING,
                                 w, h);
    if (!texture_) throw sdlError("SDL_CreateTexture failed");
    buffer_ = Image8(w, h);
  }

  // The frame at (x0, y0) over the background, which fills the rest of the window.
  void composite(const Image8& frame, int x0, int y0) {
    static const BackgroundTable table;
    for (size_t i = 0; i < buffer_.px.size(); i += 4)
      buffer_.px[i] = kBackground[0], buffer_.px[i + 1] = kBackground[1], buffer_.px[i + 2] = kBackground[2],
      buffer_.px[i + 3] = 255;
    for (int y = 0; y < frame.height; ++y) {
      const uint8_t* __restrict s = frame.px.data() + (size_t)y * frame.width * 4;
      uint8_t* __restrict d = buffer_.at(x0, y0 + y);
      for (int x = 0; x < frame.width; ++x, s += 4, d += 4) {
        const uint8_t a = s[3];
        for (int ch = 0; ch < 3; ++ch) {
          const int v = s[ch] + table.term[ch][a];  // > 255 only for invalid input (colour > alpha)
          d[ch] = (uint8_t)std::min(v, 255);
        }
      }
    }
  }

  // A line of the status or the help broken at its double spaces into lines that fit the
  // window's width.
  static std::vector<std::string> wrap(const std::string& text, int width, int scale) {
    std::vector<std::string> lines{""};
    for (size_t pos = 0; pos < text.size();) {
      size_t end = text.find("  ", pos);
      if (end == std::string::npos) end = text.size();
      const std::string part = text.substr(pos, end - pos);
      const std::string joined = lines.back().empty() ? part : lines.back() + "  " + part;
      if (lines.back().empty() || textWidth(joined, scale) + 4 * scale <= width) lines.back() = joined;
      else lines.push_back(part);
      pos = text.find_first_not_of(' ', end);
      if (pos == std::string::npos) break;
    }
    return lines;
  }

  // A dimmed strip with the lines, along the bottom edge (or the top: help), so it reads
  // over any image.
  void drawLines(const std::vector<std::string>& lines, int scale, bool top) {
    if (lines.empty() || (lines.size() == 1 && lines[0].empty())) return;
    const int pad = 2 * scale, line_h = kCellH * scale + pad;
    const int strip_h = std::min((int)lines.size() * line_h + pad, buffer_.height);
    const int y0 = top ? 0 : buffer_.height - strip_h;
    for (int y = y0; y < y0 + strip_h; ++y) {
      uint8_t* p = buffer_.at(0, y);
      for (int x = 0; x < buffer_.width * 4; ++x)
        if ((x & 3) != 3) p[x] = (uint8_t)((p[x] * kStripDim) >> 8);
    }
    for (size_t i = 0; i < lines.size(); ++i)
      drawText(buffer_, pad, y0 + pad + (int)i * line_h, lines[i], kTextColor, scale);
  }

  void translate(const SDL_Event& e, std::vector<InputEvent>& out) {
    InputEvent ev;
    // SDL stamps an event when it reads it from the server: its age says when it arrived.
    const Uint32 now = SDL_GetTicks();
    ev.at = std::chrono::steady_clock::now() - std::chrono::milliseconds(now >= e.common.timestamp ? now - e.common.timestamp : 0);
    switch (e.type) {
      case SDL_QUIT:
        ev.quit = true;
        break;
      case SDL_WINDOWEVENT:
        if (e.window.event == SDL_WINDOWEVENT_CLOSE) {
          ev.quit = true;
          break;
        }
        if (e.window.event == SDL_WINDOWEVENT_SIZE_CHANGED) {  // the farm renders at the new size
          draw();
          ev.width = e.window.data1;
          ev.height = e.window.data2;
          ev.interacting = true;  // a resize drag: sharp frames once it stops
          break;
        }
        if (e.window.event == SDL_WINDOWEVENT_EXPOSED) draw();  // nothing else keeps the frame on screen
        return;
      case SDL_MOUSEBUTTONUP:
        if (e.button.button != SDL_BUTTON_LEFT && e.button.button != SDL_BUTTON_RIGHT) return;
        break;  // released: the master renders the full frame now
      case SDL_MOUSEMOTION: {
        const bool left = e.motion.state & SDL_BUTTON_LMASK, right = e.motion.state & SDL_BUTTON_RMASK;
        if (!left && !right) return;
        ev = dragEvent(ev, e.motion.xrel, e.motion.yrel, !left);
        // Consecutive drag motions collapse into one event: the master only needs the sum.
        if (!out.empty() && addDrag(out.back(), ev)) return;
        break;
      }
      case SDL_MOUSEWHEEL: {
        int notches = e.wheel.y;
        if (e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED) notches = -notches;
        if (notches == 0) return;
        ev.zoom = std::pow(kZoomPerNotch, notches);  // positive (away from user) zooms in
        ev.interacting = true;  // wheel notches come in bursts: sharp once they stop
        break;
      }
      case SDL_KEYDOWN:
        // A held arrow steps on (scrubbing); other keys act once per press.
        if (e.key.repeat && e.key.keysym.sym != SDLK_LEFT && e.key.keysym.sym != SDLK_RIGHT) return;
        switch (e.key.keysym.sym) {
          case SDLK_1: case SDLK_KP_1: ev.quality = QualityName::Reference; break;
          case SDLK_2: case SDLK_KP_2: ev.quality = QualityName::Default; break;
          case SDLK_3: case SDLK_KP_3: ev.quality = QualityName::Fast; break;
          case SDLK_ESCAPE: case SDLK_q: ev.quit = true; break;
          case SDLK_SPACE: ev.time = proto::TimeKey::PlayPause; break;
          case SDLK_RIGHT: ev.time = proto::TimeKey::Forward; break;
          case SDLK_LEFT: ev.time = proto::TimeKey::Back; break;
          case SDLK_HOME: ev.time = proto::TimeKey::First; break;
          case SDLK_END: ev.time = proto::TimeKey::Last; break;
          case SDLK_r: ev.home = true; break;
          case SDLK_h:
            help_ = !help_;
            draw();
            return;
          default: return;
        }
        break;
      default:
        return;
    }
    out.push_back(ev);
  }


  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  SDL_Texture* texture_ = nullptr;
  Image8 buffer_;  // the window's pixels as uploaded: the scaled frame, status and help
  Image8 frame_;   // the last frame as it came
  std::string status_;
  bool help_ = false;
};

}  // namespace

std::unique_ptr<Sink> makeWindowSink(int width, int height, const std::string& title) {
  return std::make_unique<WindowSink>(width, height, title);
}

}  // namespace tessera::display
