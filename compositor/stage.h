// The compositor stage: owns one screen region per frame; gathers the pieces of frame n
// from every brick, composites them in the master's visibility order (never arrival
// order), encodes the region as strips with headers, compresses and sends it on.
#pragma once
#include <optional>

#include "common/max_intensity.h"
#include <atomic>

#include <zmq.hpp>

#include "common/net/endpoints.h"

namespace tessera::compositor {

struct StageOptions {
  Endpoints endpoints;
  std::string advertise_host;  // tcp: host renderers use to reach this compositor ("" = the base host)
  // The scene's image size (every process loads the same scene): bounds what peers may send.
  int width = 512, height = 512;
  // The scene's `blend: maximum` or `minimum`: pieces are value pixels, merged by their maxima
  // and mapped through this colour map (common/max_intensity.h; mirrored for `minimum`), seen
  // through each frame's colour window.
  std::optional<TransferFunction> maximum;
  std::string scene{};  // its sceneIdentity, said in Hello: the master refuses any other than its own
  bool minimum = false;  // with `maximum`: the scene's `blend: minimum`
};

int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop = nullptr);

}  // namespace tessera::compositor
