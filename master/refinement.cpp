#include "master/refinement.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include "master/interaction.h"

namespace tessera::master {
namespace {

double msBetween(Refinement::Clock::time_point a, Refinement::Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// What makes two frames show the same: the rung and the input number do not count, so a
// change of rung alone or an input that moved nothing issues no frame.
bool sameView(const FrameSpec& a, const FrameSpec& b) {
  return a.camera == b.camera && a.interactive == b.interactive && a.quality == b.quality &&
         a.full_width == b.full_width && a.full_height == b.full_height && a.step == b.step &&
         a.window == b.window;
}

}  // namespace

FrameSpec orbitFrame(const Scene& scene, uint64_t frame) {
  FrameSpec s;
  s.camera = scene.orbit.at(scene.camera, (int)(frame % std::max(1, scene.orbit.frames)));
  s.quality = scene.quality;
  s.width = s.full_width = scene.width;
  s.height = s.full_height = scene.height;
  s.step = scene.time.stepAt(frame, scene.series.steps);
  s.next_step = scene.time.stepAt(frame + 1, scene.series.steps);
  s.window = colorWindow(scene);
  return s;
}

void setView(proto::FrameParams& p, const FrameSpec& spec) {
  p.camera = spec.camera;
  p.quality = spec.quality;
  p.width = spec.width;
  p.height = spec.height;
  p.input_seq = spec.input_seq;
  p.input_first = spec.input_first;
  p.interactive = spec.interactive;
  p.step = (uint32_t)spec.step;
  p.next_step = (uint32_t)spec.next_step;
  p.window = spec.window;
}

Refinement::Refinement(const Camera& camera, const Quality& quality, int width, int height, const Playback& time,
                       int steps)
    : camera_(camera), home_(camera), quality_(quality), jitter_(quality.jitter), max_w_(width), max_h_(height),
      width_(width), height_(height),
      play_(time), steps_(steps), step_(time.stepAt(0, steps)) {}

Refinement::Refinement(const Scene& scene)
    : Refinement(scene.camera, scene.quality, scene.width, scene.height, scene.time, scene.series.steps) {
  windowed_ = !scene.mesh;
  if (scene.camera_fitted)
    fit_home_ = [scene](double aspect) { return fittedCamera(scene, aspect); };
}

void Refinement::issued(const FrameSpec& s) {
  last_ = s;
  first_change_ = 0;
  if (play_.play) step_ = play_.stepAt(++played_, steps_);
}

// Space plays or pauses (a finished `once` plays again from the first step); the arrows,
// Home and End pause and step. Stepping wraps around, as a loop does.
void Refinement::timeKey(proto::TimeKey key) {
  using proto::TimeKey;
  if (key == TimeKey::None || steps_ <= 1) return;
  const int first = play_.stride > 0 ? 0 : steps_ - 1, last = steps_ - 1 - first;
  // A `once` that reached its last step plays no more frames: Space plays it again at once
  // (it took a press to "pause" it first: found by review).
  const bool finished = play_.mode == Playback::Mode::Once && step_ == last &&
                        (!play_.play || (last_ && last_->step == last));  // playing: the last step issued
  if (key == TimeKey::PlayPause && (!play_.play || finished)) {
    play_.play = true;
    play_.step = finished ? first : step_;
    // A swing goes on the way it went: its phase there and back (a resumed swing always
    // headed forwards: found by review).
    if (play_.mode == Playback::Mode::Swing && !finished && heading_ != 0 && (play_.stepAt(1, steps_) - step_) * heading_ < 0)
      play_.step = 2 * (steps_ - 1) - step_;
    played_ = 0;
    step_ = play_.stepAt(0, steps_);
    if (last_ && last_->step == step_) step_ = play_.stepAt(++played_, steps_);  // shown: go on from it
    return;
  }
  if (play_.play) heading_ = play_.stepAt(played_ + 1, steps_) - step_;
  play_.play = false;
  if (key == TimeKey::Forward) step_ = (step_ + 1) % steps_;
  if (key == TimeKey::Back) step_ = (step_ + steps_ - 1) % steps_;
  if (key == TimeKey::First) step_ = 0;
  if (key == TimeKey::Last) step_ = steps_ - 1;
}

Quality Refinement::interactiveQuality(const Quality& full) {
  Quality q = namedQuality(QualityName::Default);
  q.name = QualityName::Custom;
  q.step = 2 * std::max(full.step, q.step);
  q.jitter = full.jitter;  // a moving frame at twice the step rings more, not less
  return q;
}

std::pair<int, int> Refinement::fitWindow(int ww, int wh, int max_w, int max_h) {
  const double s = std::min({1.0, (double)max_w / ww, (double)max_h / wh});
  return {std::clamp((int)std::lround(ww * s), 1, max_w), std::clamp((int)std::lround(wh * s), 1, max_h)};
}

void Refinement::input(const proto::Input& in, Clock::time_point now) {
  const auto [w, h] = in.width > 0 && in.height > 0 ? fitWindow(in.width, in.height, max_w_, max_h_)
                                                     : std::pair{width_, height_};
  const Camera home = in.home && fit_home_ ? fit_home_((double)w / h) : home_;
  Camera moved = applyInput(in.home ? home : camera_, in);  // throws before anything changes
  if (!std::isfinite(in.window_shift) || !std::isfinite(in.window_scale) || !(in.window_scale > 0))
    throw std::invalid_argument("Input with a non-finite colour window shift or a non-positive scale");
  if (windowed_) window_ = movedWindow(in.home ? home_window_ : window_, in.window_shift, in.window_scale);
  if (in.interacting && !interacting(now)) std::fill(std::begin(seen_ms_), std::end(seen_ms_), 0.0);
  camera_ = moved;
  if (in.quality) quality_ = presetKeepingJitter(namedQuality(*in.quality), jitter_);
  width_ = w, height_ = h;
  timeKey(in.time);
  held_ = in.interacting;
  last_input_ = now;
  seq_ = std::max(seq_, in.seq);
  // The input-to-present time runs from the first input that changes what the next frame shows.
  if (first_change_ == 0 && next(now)) first_change_ = in.seq;
}

ColorWindow Refinement::movedWindow(const ColorWindow& w, double shift, double scale) {
  ColorWindow out;
  // Bounds a drag cannot cross; a scene's `window` beyond them is where it starts, and a drag
  // only brings it back towards them.
  out.width = std::clamp(w.width * std::clamp(scale, 0.2, 5.0), std::min(kMinWindow, w.width), std::max(kMaxWindow, w.width));
  // At least an eighth of the window stays over the values 0..1, so it cannot be lost.
  const double reach = out.width * 3 / 8;
  out.center = std::clamp(w.center + shift * w.width, std::min(-reach, w.center), std::max(1 + reach, w.center));
  if (shift == 0 && scale == 1) out = w;  // exactly: a release moves nothing
  return out;
}

void Refinement::setSceneWindow(const ColorWindow& w) {
  if (!windowed_) return;
  window_ = home_window_ = said_window_ = w;
}

std::optional<ColorWindow> Refinement::settledWindow(Clock::time_point now) {
  if (window_ == said_window_ || interacting(now)) return std::nullopt;
  return said_window_ = window_;
}

bool Refinement::interacting(Clock::time_point now) const {
  return held_ && msBetween(last_input_, now) < kStillAfterMs;
}

std::optional<FrameSpec> Refinement::next(Clock::time_point now) const {
  FrameSpec s;
  s.camera = camera_;
  s.input_seq = seq_;
  s.input_first = first_change_;
  s.interactive = interacting(now);
  s.full_width = width_;
  s.full_height = height_;
  s.step = step_;
  s.next_step = play_.play ? play_.stepAt(played_ + 1, steps_) : step_;
  s.window = window_;
  if (s.interactive) {
    s.reduction = reduction();
    s.quality = interactiveQuality(quality_);
    s.width = std::max(1, (int)std::lround(width_ / s.reduction));
    s.height = std::max(1, (int)std::lround(height_ / s.reduction));
  } else {
    s.quality = quality_;
    s.width = width_;
    s.height = height_;
  }
  if (last_ && sameView(*last_, s)) return std::nullopt;
  return s;
}

void Refinement::interactiveDone(const FrameSpec& s, double latency_ms) {
  if (!s.interactive || s.after_cancel || s.reduction != reduction()) return;  // feedback of another rung
  double& here = seen_ms_[level_];
  here = here > 0 ? (here + latency_ms) / 2 : latency_ms;
  const double cheaper = level_ + 1 < kLevels ? seen_ms_[level_ + 1] : 0, dearer = level_ > 0 ? seen_ms_[level_ - 1] : 0;
  // The cheaper rung saved nothing against the dearer one (a frame whose cost is not in its
  // pixels, e.g. a mesh's triangles): back to the dearer one.
  if (dearer > 0 && dearer <= 1.15 * latency_ms) {
    --level_;
    return;
  }
  // Too slow: one rung cheaper, unless it was tried and saved little.
  if (latency_ms > kTargetMs * 1.25 && level_ + 1 < kLevels && (cheaper == 0 || cheaper < 0.8 * latency_ms)) {
    ++level_;
    return;
  }
  // Cost follows the pixel count: one rung dearer with room to spare, so the rungs do not flap.
  if (level_ > 0) {
    const double ratio = kReductions[level_] / kReductions[level_ - 1];
    if (latency_ms * ratio * ratio < kTargetMs * 0.8) --level_;
  }
}

}  // namespace tessera::master
