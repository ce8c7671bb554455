// Progressive refinement of an interactive run, as ParaView's level of detail does it but
// adaptive: while the user drags, the master issues reduced frames (fewer pixels at twice the
// step, one rung of a ladder measured by tessera-lod-sweep), choosing the rung from how long
// the last reduced frames took; once input stops (the button is released, or nothing moved for
// kStillAfterMs) it issues the full frame of the final camera. Input is coalesced: a frame
// always shows the newest camera, and a frame that would show nothing new is not issued.
// Plain values, no sockets; time is passed in.
#pragma once
#include <chrono>
#include <functional>
#include <optional>

#include "common/camera.h"
#include "common/quality.h"
#include "common/scene.h"
#include "common/wire/protocol.h"

namespace tessera::master {

// What one issued frame shows (the credit window keeps it, to issue the frame again).
struct FrameSpec {
  Camera camera;
  Quality quality;
  int width = 0, height = 0;            // the frame rendered
  int full_width = 0, full_height = 0;  // the full frame of this view (interactive: before reduction)
  bool interactive = false;
  uint64_t input_seq = 0;    // the newest Input it shows
  uint64_t input_first = 0;  // the first Input since the last issued frame that changed the view (0: none)
  bool after_cancel = false;  // issued behind a cancelled full frame: its time says nothing of its rung
  double reduction = 1;    // interactive frames: the image reduction factor
  int step = 0, next_step = 0;  // the volume's time step, and the one expected next (renderers prefetch it)
  ColorWindow window;           // the colour map's window
  bool operator==(const FrameSpec&) const = default;
};

// A fixed run's frame: the orbit's camera at the scene's quality, size and colour window
// (`scene`'s range fixed: the master's prepared scene).
FrameSpec orbitFrame(const Scene& scene, uint64_t frame);
// Sets what the spec decides in p: the view, the size, the inputs shown and the steps.
void setView(proto::FrameParams& p, const FrameSpec& spec);

class Refinement {
 public:
  using Clock = std::chrono::steady_clock;
  // With the button held but the mouse still, this long without input shows the full frame
  // (jupyter_rfb waits 300 ms too).
  static constexpr double kStillAfterMs = 300;
  // Interactive frames aim at this issue-to-display time. An input waits up to one frame for
  // its turn, so the oldest input a frame shows waits about twice this to be on screen: the
  // goal is 150 ms and at least 10 fps (at 80 ms, 1024x1024 on 2 cores ran at 147 ms median,
  // no margin on a shared machine; tessera-interaction-bench, README).
  static constexpr double kTargetMs = 65;
  // The ladder, cheapest last: image reduction factors, each at twice the full frame's step
  // (the Pareto front of tessera-lod-sweep on the default scene, README "Interaction").
  static constexpr double kReductions[] = {1, 1.5, 2, 3, 4};
  static constexpr int kLevels = 5, kStartLevel = 2;

  // `width` x `height`: the scene's image, the largest frame the farm renders. `time` and
  // `steps`: a time series' playback as the scene starts it.
  Refinement(const Camera& camera, const Quality& quality, int width, int height, const Playback& time = {},
             int steps = 1);
  // The scene's: its camera, quality, image, playback and steps. A scene without `camera`
  // goes home (the window's r) to its box fitted to the window's shape at that moment, as
  // it was fitted to the scene's image at the start. A volume scene's colour window moves
  // with the input's window_shift and window_scale; a mesh scene's has none.
  explicit Refinement(const Scene& scene);

  // The colour window's bounds: a width from 1/256 of the range (16 entries of the casters'
  // 4096-entry colour table, 256 levels of their 16-bit voxels) to 16 ranges, and a centre
  // that keeps some of the window over the values (a scene's `window` beyond them is kept).
  static constexpr double kMinWindow = 1.0 / 256, kMaxWindow = 16;
  static ColorWindow movedWindow(const ColorWindow& w, double shift, double scale);
  const ColorWindow& window() const { return window_; }
  // The scene's `window` once its range is known (the master has read the volume): the first
  // frames' and r's, and not news when a drag ends on it.
  void setSceneWindow(const ColorWindow& w);
  // The colour window once a drag that moved it has ended, once (the master says it).
  std::optional<ColorWindow> settledWindow(Clock::time_point now);

  // Applies a display's Input. Throws std::invalid_argument (nothing changed) for values
  // applyInput refuses. A drag that starts forgets what the rungs cost in the last one.
  void input(const proto::Input& in, Clock::time_point now);
  // The frame to issue now, or nothing when it would show the same as the last one issued.
  std::optional<FrameSpec> next(Clock::time_point now) const;
  // A frame went out: playing, the next one shows the next step.
  void issued(const FrameSpec& s);
  // A drag (or a wheel or resize burst) goes on: input within kStillAfterMs, not released.
  bool interacting(Clock::time_point now) const;
  // An interactive frame took `latency_ms` from issue to display: the next rung.
  void interactiveDone(const FrameSpec& s, double latency_ms);
  double reduction() const { return kReductions[level_]; }
  int width() const { return width_; }
  int height() const { return height_; }

  // The quality of interactive frames: the fast path (no reference precision), twice the step.
  static Quality interactiveQuality(const Quality& full);
  // The frame size for a window of ww x wh: the window's shape, shrunk to fit max_w x max_h.
  static std::pair<int, int> fitWindow(int ww, int wh, int max_w, int max_h);

 private:
  Camera camera_, home_;  // now, and the scene's (an input's `home`)
  std::function<Camera(double aspect)> fit_home_;  // set: home fits the scene's box to this aspect
  Quality quality_;
  bool jitter_ = false;  // the scene's quality.jitter, kept through the quality keys' presets
  ColorWindow window_, home_window_, said_window_;
  bool windowed_ = true;  // the colour window moves (not a mesh scene)
  int max_w_, max_h_, width_, height_;
  bool held_ = false;
  Clock::time_point last_input_{};
  uint64_t seq_ = 0, first_change_ = 0;
  int level_ = kStartLevel;
  double seen_ms_[kLevels] = {};  // recent interactive frame times per rung (0: not seen)
  std::optional<FrameSpec> last_;
  // A time series: keys pause, play and step; every issued frame advances a playing series.
  void timeKey(proto::TimeKey key);
  Playback play_;        // play_.step: where the playing started
  int steps_ = 1, step_ = 0;
  int heading_ = 0;      // where playing went when it paused: > 0 up the steps, < 0 down
  uint64_t played_ = 0;  // frames issued since
};

}  // namespace tessera::master
