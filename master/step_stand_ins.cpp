// Stand-ins for steps that mixed a frame (see step_stand_ins.h).
#include "master/step_stand_ins.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

namespace tessera::master {

bool StepStandIns::frameShown(int asked, const std::set<uint32_t>& shown) {
  if (shown.size() < 2 || !shown.count((uint32_t)asked) || stand_in_.count(asked)) return false;
  // The renderers that failed showed their last good step: the one the others' is not.
  for (uint32_t s : shown)
    if ((int)s != asked) return stand_in_.emplace(asked, (int)s).second;
  return false;
}

void StepStandIns::learn(const std::vector<Metrics::MixedSteps>& mixed) {
  for (const auto& m : mixed)
    if (frameShown(m.asked, m.shown))
      spdlog::warn("frame {} showed steps {} together: a renderer could not read step {} in its bricks (its error is "
                   "above) and showed its last good step; from now on every renderer shows step {} in its place",
                   m.frame, fmt::join(m.shown, " and "), m.asked, stepFor(m.asked));
}

int StepStandIns::stepFor(int step) const {
  // A stand-in may itself have mixed a frame since: follow, at most once per known step.
  for (size_t hops = 0; hops <= stand_in_.size() && stand_in_.count(step); ++hops) step = stand_in_.at(step);
  return step;
}

FrameSpec StepStandIns::sent(const FrameSpec& spec) const {
  FrameSpec s = spec;
  s.step = stepFor(spec.step);
  s.next_step = stepFor(spec.next_step);
  return s;
}

}  // namespace tessera::master
