// The display stage: routes the compositors' strips into the frame by their headers
// alone, presents it (window or PNG files), shows fps/latency/per-stage ms, and returns
// FrameDone to the master (the credit that lets the next frame start).
#pragma once
#include <array>
#include <atomic>
#include <optional>
#include <string>

#include <zmq.hpp>

#include "common/net/endpoints.h"

namespace tessera::display {

struct StageOptions {
  Endpoints endpoints;
  std::string out_dir = "out";  // PNG frames when there is no window
  // auto: a window when a display server answers, else PNG files; on: a window or an error.
  enum class Window { Auto, On, Off } window = Window::Auto;
  std::optional<std::array<double, 3>> background;  // PNG: composite over this colour
  // The scene's image size (every process loads the same scene): bounds what peers may send.
  int width = 512, height = 512;
  int steps = 1;  // a time series' steps: the status line shows the frame's
  bool premultiplied = false;  // also write frame_NNNNNN.pam (exact premultiplied rgba8)
  std::string web{};      // HOST:PORT of the web view, beside the window or PNG files ("": none)
  std::string web_token{};  // what its viewers must present
  std::string scene{};      // its sceneIdentity, said in Hello: the master refuses any other than its own
};

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop = nullptr);

}  // namespace tessera::display
