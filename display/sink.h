// Where the display stage puts finished frames: an SDL2 window or a folder of PNG files.
// A Sink is used from one thread (the display loop). Frames are premultiplied rgba8.
#pragma once
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/image.h"
#include "common/scene.h"
#include "common/wire/protocol.h"

namespace tessera::display {

// Input as the window and the web view read it: drag sensitivity, and what one wheel notch
// ("in", away from the user) does to the eye distance.
constexpr double kDegreesPerPixel = 0.3;
constexpr double kZoomPerNotch = 0.9;
// A right-button drag sets the colour window, as CT viewers' window/level drag does: right
// widens it (a 100-pixel drag 1.65 times), up raises its level (a 100-pixel drag by a quarter
// of its width).
constexpr double kWindowScalePerPixel = 1.005;
constexpr double kWindowShiftPerPixel = 0.0025;

struct InputEvent {
  double orbit_dx = 0, orbit_dy = 0;  // degrees (drag)
  double zoom = 1;                    // multiply eye distance (wheel)
  std::optional<QualityName> quality;  // keys 1/2/3: reference, default, fast
  bool quit = false;                  // window closed, Esc or q
  bool interacting = false;           // a drag, wheel or resize goes on (false: button released, a key)
  int width = 0, height = 0;          // the window's new size (0: unchanged)
  proto::TimeKey time = proto::TimeKey::None;  // Space, arrows, Home, End: a time series' playback
  bool home = false;                  // r: the scene's camera and colour window again
  double window_shift = 0, window_scale = 1;  // right drag: the colour window (proto::Input)
  std::chrono::steady_clock::time_point at;  // when the (first merged) event reached the display
  // From a web page: the page's number for its load and the number it gave this (first merged)
  // input, so that the page can time input-to-present itself (page 0: not from a page).
  uint32_t page = 0;
  uint64_t page_input = 0;
};

// What the display knows of a frame it presents.
struct Shown {
  uint64_t id = 0;
  std::string status;   // the fps/latency/per-stage line drawn on screen
  bool moving = false;  // a reduced frame while the camera moves (the web view sends it lossy)
  int full_width = 0, full_height = 0;  // the last full-quality frame's size (0: none yet)
  // The first input this frame answers, if it came from a web page (InputEvent::page, page_input).
  uint32_t page = 0;
  uint64_t page_input = 0;
  double input_ms = 0;  // from the display receiving that input to this frame going to the sinks
};

// A drag and nothing else: consecutive ones collapse into one (the master needs the sum).
inline bool isDrag(const InputEvent& ev) {
  return ev.interacting && ev.zoom == 1 && !ev.quality && !ev.quit && ev.width == 0 && ev.time == proto::TimeKey::None && !ev.home;
}
// Adds drag `ev` to `last` if both are drags; false (nothing changed) otherwise.
inline bool addDrag(InputEvent& last, const InputEvent& ev) {
  if (!isDrag(last) || !isDrag(ev)) return false;
  last.orbit_dx += ev.orbit_dx;
  last.orbit_dy += ev.orbit_dy;
  last.window_shift += ev.window_shift;
  last.window_scale = std::clamp(last.window_scale * ev.window_scale, 1e-3, 1e3);  // the master takes 0.2..5 a step
  return true;
}
// `ev` (its time and page) as a drag of dx, dy pixels: the left button's orbits, the right
// button's sets the colour window.
inline InputEvent dragEvent(InputEvent ev, double dx, double dy, bool right) {
  if (right) {
    ev.window_scale = std::pow(kWindowScalePerPixel, std::clamp(dx, -1000.0, 1000.0));  // a web page's dx may be 1e4
    ev.window_shift = -dy * kWindowShiftPerPixel;  // screen y grows downwards
  } else {
    ev.orbit_dx = dx * kDegreesPerPixel;
    ev.orbit_dy = dy * kDegreesPerPixel;
  }
  ev.interacting = true;
  return ev;
}

class Sink {
 public:
  virtual ~Sink() = default;
  // Shows or writes `frame`. A window scales it to fit (bilinear, centred, the same shape);
  // files keep its size.
  virtual void present(const Image8& frame, const Shown& shown) = 0;
  // Input since the last call (windows and the web view).
  virtual std::vector<InputEvent> poll() { return {}; }
  virtual bool interactive() const { return false; }  // a window: it takes input
};

// Writes <dir>/frame_<id 6 digits>.png (straight alpha, or composited over background) and,
// with `premultiplied`, frame_<id>.pam beside it: the exact rgba8 values (see writePam).
std::unique_ptr<Sink> makePngSink(const std::string& dir,
                                  std::optional<std::array<double, 3>> background = std::nullopt,
                                  bool premultiplied = false);
// Opens a window of the image's size; throws std::runtime_error naming the reason if no X11 or
// Wayland server answers. Trying is the only probe: a separate probe's connection, once closed,
// can make an X server reset under the window that follows.
std::unique_ptr<Sink> makeWindowSink(int width, int height, const std::string& title);

// The web view: serves the page and a WebSocket on `address` (HOST:PORT) for viewers that
// present `token`; frames are shown over `background` (the PNG sink's, so that the page's
// still frame is the PNG file's pixels). Throws std::runtime_error if it cannot listen.
std::unique_ptr<Sink> makeWebSink(const std::string& address, const std::string& token,
                                  const std::array<double, 3>& background);
// Every frame to each sink in turn, the input of all of them (a window or PNG files, and the
// web view beside them).
std::unique_ptr<Sink> makeTeeSink(std::vector<std::unique_ptr<Sink>> sinks);

}  // namespace tessera::display
