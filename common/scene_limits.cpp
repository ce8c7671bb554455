// Scene limits (issue 8): values that would make a renderer throw, allocate without bound or
// draw an empty image are refused where the scene is read, naming the value and the limit.
#include <cmath>
#include <cstdio>

#include "common/scene.h"
#include "common/wire/protocol.h"

namespace tessera {

static_assert(kMaxImagePixels * 16 == proto::kMaxPayload, "a whole-image rgba32f piece must fit one message");

namespace {
std::string shown(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.15g", v);
  return b;
}
std::string inRange(double v, double lo, double hi, const std::string& unit) {
  if (v >= lo && v <= hi) return "";
  return shown(v) + " must be in [" + shown(lo) + ", " + shown(hi) + "]" + unit;
}
}  // namespace

std::string stepProblem(double step) {
  if (step >= kMinStep && step <= kMaxStep) return "";
  return inRange(step, kMinStep, kMaxStep, " world units") +
         " (the volume spans 1: a smaller step exceeds 2^20 samples per ray, a larger one leaves fewer than 4)";
}

std::string imageSizeProblem(int width, int height) {
  const long long pixels = (long long)width * height;
  if (pixels <= kMaxImagePixels) return "";
  return std::to_string(width) + " x " + std::to_string(height) + " = " + std::to_string(pixels) +
         " pixels; a whole-image rgba32f piece would be " + std::to_string(pixels * 16) +
         " bytes, over the wire's message limit of " + std::to_string(proto::kMaxPayload) + " bytes: at most " +
         std::to_string(kMaxImagePixels) + " pixels";
}

KeyProblem cameraProblem(const Camera& c) {
  // Distance first: it is what a far-away eye breaks (the view direction, then "parallel").
  const Vec3 d = c.target - c.eye;
  const double dist = std::hypot(d.x, d.y, d.z);
  if (!std::isfinite(dist))
    return {"camera.eye", "distance to the target overflows (eye and target must be within " +
                              shown(kMaxCameraDistance) + " of each other)"};
  if (dist > 0 && !(dist >= kMinCameraDistance && dist <= kMaxCameraDistance))
    return {"camera.eye", "distance to the target is " + shown(dist) + ", out of range [" + shown(kMinCameraDistance) +
                              ", " + shown(kMaxCameraDistance) + "]"};
  for (const auto& [key, v] : {std::pair{"camera.eye", c.eye}, std::pair{"camera.target", c.target}})
    for (double x : {v.x, v.y, v.z})
      if (!(std::abs(x) <= kMaxCameraDistance))
        return {key, "coordinate " + shown(x) + " is out of range (|coordinate| <= " + shown(kMaxCameraDistance) +
                         "; the volume spans 1)"};
  if (c.orthographic) {
    if (std::string p = inRange(c.height, kMinOrthoHeight, kMaxOrthoHeight, ""); !p.empty())
      return {"camera.height", p};
  } else if (std::string p = inRange(c.fov, kMinFov, kMaxFov, " degrees"); !p.empty()) {
    return {"camera.fov", p};
  }
  return {};
}

std::string farmAccuracyProblem(const Quality& q, int renderers) {
  // One brick casts exactly tessera-render's rays; with more, every brick stops on its own
  // and what lies behind a stopped front brick (up to 1 - e of the pixel) still shows.
  const double kMinFarmEarlyTermination = 1.0 - 1.0 / 255;
  if (renderers <= 1 || q.early_termination > 1 || q.early_termination >= kMinFarmEarlyTermination) return "";
  char levels[32];
  std::snprintf(levels, sizeof levels, "%.2f", (1 - q.early_termination) * 255);
  return "quality.early_termination: " + shown(q.early_termination) + " with " + std::to_string(renderers) +
         " renderers lets each brick stop its rays on its own, an error of up to " + levels +
         " levels (of 255) against one process, over the farm's 1-level contract; use >= 0.9961 or one renderer";
}

}  // namespace tessera
