// Time series: which step a frame shows, and where a step's samples are.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <fmt/format.h>

#include "common/io/volume_files.h"
#include "common/scene.h"

namespace tessera {
namespace {

long long floorMod(long long a, long long m) { return ((a % m) + m) % m; }

std::string dimsText(const std::array<int, 3>& d) {
  std::string s = "[";  // appended: GCC 12 warns falsely (-Wrestrict) on "lit" + string&&
  s += std::to_string(d[0]) + ", " + std::to_string(d[1]) + ", " + std::to_string(d[2]) + "]";
  return s;
}

// Step t's header against step 0's: a series has one shape. The headers' spacing matters
// only when the scene does not give one for every step.
void checkSameShape(const RawVolumeSpec& step, const RawVolumeSpec& first, const std::string& first_file,
                    bool spacing_given) {
  auto differ = [&](const std::string& field, const std::string& a, const std::string& b) {
    throw std::runtime_error(step.file + ": " + field + " " + a + " differs from step 0's " + b + " (" + first_file +
                             "); every step of a series needs the same dims and type, and the same spacing unless "
                             "volume.spacing gives one for all");
  };
  if (step.dims != first.dims) differ("dims", dimsText(step.dims), dimsText(first.dims));
  if (step.type != first.type) differ("type", voxelTypeName(step.type), voxelTypeName(first.type));
  // Spacings equal to float32's precision are one (headers written by different tools round
  // 0.5 to 0.50000006): the steps are drawn with step 0's.
  for (int a = 0; a < 3 && !spacing_given; ++a)
    if (!(std::fabs(step.spacing[a] - first.spacing[a]) <= 1e-6 * std::fabs(first.spacing[a])))
      differ(fmt::format("spacing[{}]", a), fmt::format("{:.7g}", step.spacing[a]), fmt::format("{:.7g}", first.spacing[a]));
}

}  // namespace

const char* playbackModeName(Playback::Mode m) {
  switch (m) {
    case Playback::Mode::Loop: return "loop";
    case Playback::Mode::Once: return "once";
    case Playback::Mode::Swing: return "swing";
  }
  return "?";
}

int Playback::stepAt(uint64_t frame, int steps) const {
  if (!play || steps <= 1) return std::clamp(step, 0, std::max(0, steps - 1));
  // Frames of a run are at most 1e6 and |stride| <= 1e6: no overflow in 64 bits.
  const long long s = step + (long long)frame * stride;
  switch (mode) {
    case Mode::Loop: return (int)floorMod(s, steps);
    case Mode::Once: return (int)std::clamp<long long>(s, 0, steps - 1);
    case Mode::Swing: {
      const long long period = 2ll * (steps - 1), p = floorMod(s, period);
      return (int)(p < steps ? p : period - p);
    }
  }
  return 0;
}

int Playback::onePass(int steps) const {
  if (!play || steps <= 1) return 1;
  const long long span = mode == Mode::Swing ? 2ll * (steps - 1) : steps, a = std::llabs((long long)stride);
  return (int)std::max(1ll, (span + a - 1) / a);
}

std::variant<RawVolumeSpec, GeneratorSpec> stepVolume(const Scene& scene, int step) {
  const TimeSeries& t = scene.series;
  if (step < 0 || step >= t.steps)
    throw std::runtime_error("step " + std::to_string(step) + " is outside the series' 0.." + std::to_string(t.steps - 1));
  if (const auto* g = std::get_if<GeneratorSpec>(&scene.volume)) {
    GeneratorSpec s = *g;
    s.time = t.steps > 1 ? (double)step / t.steps : 0;  // one period over the steps: a loop closes
    return s;
  }
  RawVolumeSpec s = std::get<RawVolumeSpec>(scene.volume);
  s.read_once = t.steps > 1;
  if (step == 0) return s;
  if (t.files.empty()) {  // a 4-D file: step t's samples follow step t-1's
    s.offset += (uint64_t)step * t.step_bytes;
    return s;
  }
  const std::string& file = t.files[step];
  if (volumeFormatOf(file) != s.format)
    throw std::runtime_error(file + ": format differs from step 0's (" + s.file + "); every step needs one format");
  if (s.format == VolumeFormat::Raw) {
    s.file = file;  // the reader checks its size against dims x type
    return s;
  }
  if (std::string why = notRegularFile(file); !why.empty()) throw std::runtime_error(file + ": " + why);
  RawVolumeSpec h = readVolumeHeader(file);
  // Against the scene's own spec, step 0's header as read at load: that file may be gone since.
  checkSameShape(h, s, t.files[0], s.spacing_given);
  // The scene's keys hold for every step.
  h.spacing = s.spacing;
  h.has_range = s.has_range;
  h.range = s.range;
  h.read_once = s.read_once;
  return h;
}

}  // namespace tessera
