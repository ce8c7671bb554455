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
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "common/net/stage_link.h"
#include "common/scene.h"
#include "common/wire/protocol.h"
#include "master/master.h"
#include "master/plan.h"

namespace tessera::master {

struct Prepared {
  Scene scene;                              // with the volume's range fixed; the plan refers to its tf
  std::unique_ptr<Plan> plan;
  std::array<double, 2> volume_range{0, 0};  // for the Welcome: {0, 0} none
};

// While the volume is read no stage can be welcomed (the Welcome carries its range): the
// master handles its control messages as always (strangers refused, bad messages dropped)
// and holds the Hellos of its run here, the newest per connection.
class HeldHellos {
 public:
  // False, and nothing held, for a new connection past kMost.
  bool hold(const std::string& identity, const proto::Hello& hello);
  // Stages say Hello every StageLink::kHelloEveryS: one silent for twice that is gone (it
  // died while the volume was read) and is left out. The others, first come first.
  std::vector<std::pair<std::string, proto::Hello>> live(double silent_s = 2 * StageLink::kHelloEveryS);

 private:
  struct Held {
    Clock::time_point first, last;
    proto::Hello hello;
  };
  std::map<std::string, Held> held_;  // by the connection's routing id
  static constexpr size_t kMost = 4096;
};

// What the reading threw (a bad volume file), as await() rethrows it.
struct ReadingFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Preparation {
 public:
  explicit Preparation(const MasterOptions& opt);  // starts reading; `opt` must outlive this
  ~Preparation();                                  // waits for the reading to end

  // Calls `meanwhile` every 100 ms until the reading ends, saying every 10 s how long it
  // takes. Throws ReadingFailed with what the reading threw (a bad file); nullptr when stopped meanwhile
  // (the reading is then cancelled: it ends at its next slab).
  std::unique_ptr<Prepared> await(const std::atomic<bool>* stop, const std::function<void()>& meanwhile);

 private:
  std::atomic<bool> cancel_{false};
  std::future<std::unique_ptr<Prepared>> reading_;
};

}  // namespace tessera::master
