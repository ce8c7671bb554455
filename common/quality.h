// How a frame is sampled (the named qualities) and how geometry is anti-aliased: the
// values the wire carries, kept apart from the scene model so the protocol needs only these.
#pragma once
#include <cstdint>
#include <string>

namespace tessera {

// The named qualities; Custom is a scene's own step/termination/skipping.
enum class QualityName : uint8_t { Reference = 1, Default = 2, Fast = 3, Custom = 4, Last = Custom };
const char* qualityName(QualityName q);  // "reference" | "default" | "fast" | "custom"

struct Quality {
  QualityName name = QualityName::Default;
  double step = 1.0 / 256;         // world units along the ray
  double early_termination = 1.0 - 0.5 / 255;  // stop when accumulated alpha >= this; > 1 disables
  bool skip_empty = true;
  bool reference = false;          // double precision, no skipping, no early termination
  bool jitter = false;             // each pixel's samples offset within the step (pixelJitter), not mid-step
  bool operator==(const Quality&) const = default;
};
// reference: step L0/16, no ET, no skipping; default: step L0, ET 1 - 0.5/255; fast: step 2*L0,
// ET as default (every preset is farm-exact: see farmAccuracyProblem).
Quality namedQuality(QualityName name);         // Custom: std::invalid_argument
Quality namedQuality(const std::string& name);  // a preset by its word; std::invalid_argument names it
// A preset chosen over a scene's quality (tessera-render --quality, the window's keys): its step
// and termination, with the scene's `jitter` (Custom then), except for the reference, which
// samples mid-step.
Quality presetKeepingJitter(Quality preset, bool scene_jitter);

// Anti-aliasing of geometry: none | msaa (samples 2 or 4) | ssaa (k x k, samples = k) | fft
// (Gaussian low-pass of the final image, sigma in pixels).
enum class AaMethod : uint8_t { None, Msaa, Ssaa, Fft };
const char* aaMethodName(AaMethod m);  // "none" | "msaa" | "ssaa" | "fft"
// The method a word names; std::invalid_argument naming the word and the choices.
AaMethod parseAaMethod(const std::string& word);
struct Antialiasing {
  AaMethod method = AaMethod::None;
  int samples = 1;
  double sigma = 0.6;
  bool operator==(const Antialiasing&) const = default;
};

}  // namespace tessera
