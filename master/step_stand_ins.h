// Steps some renderers could not read while others could (a NaN in one brick, a gzip stream
// cut short past the first bricks). Each renderer shows its own last good step in place of a
// bad one, so such a frame mixed two steps. Once a frame shows that, the whole farm is asked
// for the step those renderers showed, whenever the bad one comes round, for the rest of the
// run: no frame issued after the master hears of it mixes (those already in flight may). A
// step every renderer failed is still asked for as it is (its file may yet appear, as in a
// live acquisition), since every renderer then shows the same step.
#pragma once
#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "master/metrics.h"
#include "master/refinement.h"

namespace tessera::master {

class StepStandIns {
 public:
  // A frame asked for `asked` and its renderers (those with bricks) showed `shown`. True if
  // this made `asked` a stand-in's step (the first mixed frame of it).
  bool frameShown(int asked, const std::set<uint32_t>& shown);
  // The same for each mixed frame, with a warning for each new stand-in.
  void learn(const std::vector<Metrics::MixedSteps>& mixed);
  // The step to ask the renderers for in place of `step` (`step` itself unless it mixed).
  int stepFor(int step) const;
  // `spec` as the renderers are to render it: its step and next step replaced by stand-ins.
  FrameSpec sent(const FrameSpec& spec) const;

 private:
  std::map<int, int> stand_in_;
};

}  // namespace tessera::master
