// The master: owns the scene, camera and work assignment; registers stages (membership,
// heartbeats), broadcasts FrameParams, keeps at most `in_flight` frames in flight, and writes
// one JSON line of metrics per frame. run() blocks until the last frame is done.
// The parts: membership.h, credit_window.h, sort_last_plan.h / sort_first_plan.h, metrics.h.
#pragma once
#include <atomic>
#include <string>

#include <zmq.hpp>

#include "common/wire/codec.h"
#include "common/net/endpoints.h"
#include "common/wire/protocol.h"
#include "common/scene.h"
#include "master/credit_window.h"

namespace tessera::master {

struct MasterOptions {
  Scene scene;
  Endpoints endpoints;
  int renderers = 1, compositors = 1;
  int frames = -1;          // -1: the scene's orbit frames; 0: interactive (until the display quits)
  int in_flight = 3;        // frames in flight
  Codec codec = Codec::Lzo;
  // rgba16f: rgba8 pieces round twice before the final rounding (up to 1.5 levels),
  // which breaks the 1/255 sort-last contract; half floats keep it (see README).
  proto::PixelFormat format = proto::PixelFormat::RGBA16F;
  // Sort-last: renderers composite among themselves by binary swap (swap_plan.h), any count
  // of them, one brick each; direct send when a renderer has no swap socket (and when false).
  bool binary_swap = false;
  bool balance = true;      // sort-last: compositor regions by active pixels; sort-first: tiles by cost
  int tiles_per_renderer = 1;  // sort-first tiles = renderers x this
  std::string metrics_path; // JSON lines; "" = none
  std::string run;          // this farm's identity (TESSERA_RUN): a Hello of another run is refused
  double heartbeat_timeout_s = 3.0;
  double start_timeout_s = 60.0;
  DeadlineOptions deadline;  // a frame late past this blames the stage that did not deliver
};

// Returns the process exit code. `stop` (optional) ends it early (signals, tests).
int run(const MasterOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop = nullptr);

}  // namespace tessera::master
