// The named qualities and anti-aliasing methods: their words in scene files, on the command
// line and in logs, and what each named quality sets.
#include <stdexcept>
#include <string>

#include "common/quality.h"
#include "common/transfer_function.h"  // kL0

namespace tessera {

const char* qualityName(QualityName q) {
  switch (q) {
    case QualityName::Reference: return "reference";
    case QualityName::Default: return "default";
    case QualityName::Fast: return "fast";
    case QualityName::Custom: break;
  }
  return "custom";
}

Quality namedQuality(QualityName name) {
  Quality q;
  q.name = name;
  switch (name) {
    case QualityName::Reference:
      q.step = kL0 / 16;
      q.early_termination = 2.0;  // > 1: never terminates
      q.skip_empty = false;
      q.reference = true;
      return q;
    case QualityName::Default:
      q.step = kL0;
      // Stop once what is left of the ray cannot move an 8-bit value by half a level; this
      // also keeps bricks terminated separately within 1/255 of one whole-volume ray.
      q.early_termination = 1.0 - 0.5 / 255;
      return q;
    case QualityName::Fast:
      // Speed from the step alone: a lower early termination would let bricks stop separately
      // and the farm would differ from one process by (1 - ET) * 255 levels (13 at 0.95).
      q.step = 2 * kL0;
      q.early_termination = 1.0 - 0.5 / 255;
      return q;
    case QualityName::Custom: break;
  }
  throw std::invalid_argument("'custom' is not a named quality (reference | default | fast)");
}

Quality presetKeepingJitter(Quality preset, bool scene_jitter) {
  if (scene_jitter && !preset.reference) preset.jitter = true, preset.name = QualityName::Custom;
  return preset;
}

Quality namedQuality(const std::string& name) {
  for (QualityName q : {QualityName::Reference, QualityName::Default, QualityName::Fast})
    if (name == qualityName(q)) return namedQuality(q);
  throw std::invalid_argument("unknown quality '" + name + "' (reference | default | fast)");
}

const char* aaMethodName(AaMethod m) {
  switch (m) {
    case AaMethod::Msaa: return "msaa";
    case AaMethod::Ssaa: return "ssaa";
    case AaMethod::Fft: return "fft";
    case AaMethod::None: break;
  }
  return "none";
}

AaMethod parseAaMethod(const std::string& word) {
  for (AaMethod m : {AaMethod::None, AaMethod::Msaa, AaMethod::Ssaa, AaMethod::Fft})
    if (word == aaMethodName(m)) return m;
  throw std::invalid_argument("expected none, msaa, ssaa or fft, got '" + word + "'");
}

}  // namespace tessera
