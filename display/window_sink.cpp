// SDL2 window sink: premultiplied frames composited over a dark background, a status strip
// drawn with the built-in font, and mouse/keyboard input translated to InputEvents.
#include <SDL.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "display/font.h"
#include "display/sink.h"

namespace tessera::display {
namespace {

constexpr double kDegreesPerPixel = 0.3;  // drag sensitivity
constexpr double kZoomPerNotch = 0.9;     // wheel "in" shrinks the eye distance
constexpr uint8_t kBackground[3] = {32, 32, 36};  // a window has no alpha: show over dark grey
constexpr uint8_t kStripDim = 96;  // strip pixels keep 96/256 of their colour behind the text
constexpr std::array<uint8_t, 4> kTextColor = {230, 230, 230, 255};

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
                               width, height, SDL_WINDOW_SHOWN);
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

  void present(const Image8& frame, uint64_t /*id*/, const std::string& status) override {
    if (frame.width <= 0 || frame.height <= 0) return;
    if (frame.px.size() != (size_t)frame.width * frame.height * 4)
      throw std::invalid_argument("display window: frame pixel buffer has the wrong size");
    ensureTexture(frame.width, frame.height);
    composite(frame);
    drawStatus(status);
    if (SDL_UpdateTexture(texture_, nullptr, buffer_.px.data(), buffer_.width * 4) != 0)
      throw sdlError("SDL_UpdateTexture failed");
    redraw();
  }

  std::vector<InputEvent> poll() override {
    std::vector<InputEvent> out;
    SDL_Event e;
    // Bounded by what is queued now; events that arrive meanwhile wait for the next call.
    for (int n = 0; n < 4096 && SDL_PollEvent(&e); ++n) translate(e, out);
    return out;
  }

 private:
  void ensureTexture(int w, int h) {
    if (texture_ && w == buffer_.width && h == buffer_.height) return;
    if (texture_) SDL_DestroyTexture(texture_);
    // RGBA32 is R,G,B,A in memory on any endianness, matching Image8's byte order.
    texture_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGBA32, SDL_TEXTUREACCESS_STREAMING,
                                 w, h);
    if (!texture_) throw sdlError("SDL_CreateTexture failed");
    buffer_ = Image8(w, h);
  }

  void composite(const Image8& frame) {
    static const BackgroundTable table;
    const size_t n = (size_t)frame.width * frame.height;
    const uint8_t* __restrict s = frame.px.data();
    uint8_t* __restrict d = buffer_.px.data();
    for (size_t i = 0; i < n; ++i, s += 4, d += 4) {
      const uint8_t a = s[3];
      for (int ch = 0; ch < 3; ++ch) {
        const int v = s[ch] + table.term[ch][a];  // > 255 only for invalid input (colour > alpha)
        d[ch] = (uint8_t)std::min(v, 255);
      }
      d[3] = 255;
    }
  }

  // A dimmed strip along the bottom edge with the status text, so it reads over any image.
  void drawStatus(const std::string& status) {
    if (status.empty()) return;
    const int scale = buffer_.width >= 800 ? 2 : 1;
    const int pad = 2 * scale;
    const int strip_h = std::min(kCellH * scale + 2 * pad, buffer_.height);
    for (int y = buffer_.height - strip_h; y < buffer_.height; ++y) {
      uint8_t* p = buffer_.at(0, y);
      for (int x = 0; x < buffer_.width * 4; ++x)
        if ((x & 3) != 3) p[x] = (uint8_t)((p[x] * kStripDim) >> 8);
    }
    drawText(buffer_, pad, buffer_.height - strip_h + pad, status, kTextColor, scale);
  }

  void redraw() {
    if (!texture_) return;
    SDL_RenderClear(renderer_);
    SDL_RenderCopy(renderer_, texture_, nullptr, nullptr);  // scales if the window was resized
    SDL_RenderPresent(renderer_);
  }

  void translate(const SDL_Event& e, std::vector<InputEvent>& out) {
    InputEvent ev;
    switch (e.type) {
      case SDL_QUIT:
        ev.quit = true;
        break;
      case SDL_WINDOWEVENT:
        if (e.window.event == SDL_WINDOWEVENT_CLOSE) {
          ev.quit = true;
          break;
        }
        // Nothing else keeps the last frame on screen after an expose or resize.
        if (e.window.event == SDL_WINDOWEVENT_EXPOSED ||
            e.window.event == SDL_WINDOWEVENT_SIZE_CHANGED)
          redraw();
        return;
      case SDL_MOUSEMOTION:
        if (!(e.motion.state & SDL_BUTTON_LMASK)) return;
        // Consecutive drag motions collapse into one event: the master only needs the sum.
        if (!out.empty() && isDragOnly(out.back())) {
          out.back().orbit_dx += e.motion.xrel * kDegreesPerPixel;
          out.back().orbit_dy += e.motion.yrel * kDegreesPerPixel;
          return;
        }
        ev.orbit_dx = e.motion.xrel * kDegreesPerPixel;
        ev.orbit_dy = e.motion.yrel * kDegreesPerPixel;
        break;
      case SDL_MOUSEWHEEL: {
        int notches = e.wheel.y;
        if (e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED) notches = -notches;
        if (notches == 0) return;
        ev.zoom = std::pow(kZoomPerNotch, notches);  // positive (away from user) zooms in
        break;
      }
      case SDL_KEYDOWN:
        if (e.key.repeat) return;
        switch (e.key.keysym.sym) {
          case SDLK_1: case SDLK_KP_1: ev.quality = QualityName::Reference; break;
          case SDLK_2: case SDLK_KP_2: ev.quality = QualityName::Default; break;
          case SDLK_3: case SDLK_KP_3: ev.quality = QualityName::Fast; break;
          case SDLK_ESCAPE: case SDLK_q: ev.quit = true; break;
          default: return;
        }
        break;
      default:
        return;
    }
    out.push_back(ev);
  }

  static bool isDragOnly(const InputEvent& ev) {
    return ev.zoom == 1 && !ev.quality && !ev.quit;
  }

  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  SDL_Texture* texture_ = nullptr;
  Image8 buffer_;  // opaque copy of the last frame with the status strip, as uploaded
};

}  // namespace

std::unique_ptr<Sink> makeWindowSink(int width, int height, const std::string& title) {
  return std::make_unique<WindowSink>(width, height, title);
}

}  // namespace tessera::display
