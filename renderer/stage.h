// The renderer stage of the farm: renders its bricks for every FrameParams, crops each
// image to its active region, splits it by the compositors' regions (direct send),
// compresses and sends one Piece per (brick, compositor) — empty parts as empty pieces.
// With a binary-swap plan it composites with the other renderers instead (swap_exchange.h),
// rendering its next frame on a worker thread while the rounds wait for partners' pieces,
// and sends its finished band straight to the display as strips.
#pragma once
#include <atomic>

#include <zmq.hpp>

#include "common/net/endpoints.h"
#include "common/scene.h"
#include "renderer/volume/backend.h"

namespace tessera::renderer {

struct StageOptions {
  Scene scene;
  Endpoints endpoints;
  int threads = 0;  // ray-casting threads; 0 = all cores
  BackendKind backend = BackendKind::Cpu;  // volume scenes
  int cache_mb = 1024;  // time series: voxels held for steps besides the one rendered (step_cache.h)
  std::string advertise_host = "";  // tcp: host the other renderers use to reach this one ("" = the base host)
};

// Returns the exit code: 0 on Shutdown or stop, 1 if it could not join the farm.
int runStage(const StageOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop = nullptr);

}  // namespace tessera::renderer
