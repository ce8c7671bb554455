// What the master reads before it answers any stage: a volume file's value range (when the
// scene gives no `range`; every renderer gets it in its Welcome and reads only its bricks)
// and the block summary the plan splits bricks by. For a big file on a slow file server
// that takes minutes, so it runs on a thread of its own while the master probes: stages
// that hear probes keep waiting for their Welcome (StageLink::join).
#pragma once
#include <array>
#include <atomic>
#include <functional>
#include <future>
#include <memory>

#include "common/scene.h"
#include "master/master.h"
#include "master/plan.h"

namespace tessera::master {

struct Prepared {
  Scene scene;                              // with the volume's range fixed; the plan refers to its tf
  std::unique_ptr<Plan> plan;
  std::array<double, 2> volume_range{0, 0};  // for the Welcome: {0, 0} none
};

class Preparation {
 public:
  explicit Preparation(const MasterOptions& opt);  // starts reading; `opt` must outlive this
  ~Preparation();                                  // waits for the reading to end

  // Calls `meanwhile` every 100 ms until the reading ends, saying every 10 s how long it
  // takes. Rethrows what the reading threw (a bad file); nullptr when stopped meanwhile.
  std::unique_ptr<Prepared> await(const std::atomic<bool>* stop, const std::function<void()>& meanwhile);

 private:
  std::future<std::unique_ptr<Prepared>> reading_;
};

}  // namespace tessera::master
