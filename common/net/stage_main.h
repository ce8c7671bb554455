// The skeleton every farm process's main shares: the scene and --endpoints options, flag
// parsing, a ZeroMQ context with CURVE on when the endpoints leave this host, the stop
// signals, and one way to fail (the error logged as one line, exit code 1).
#pragma once
#include <atomic>
#include <functional>
#include <string>

#include <CLI/CLI.hpp>
#include <zmq.hpp>

#include "common/net/endpoints.h"
#include "common/scene.h"

namespace tessera {

struct StageArgs {
  std::string scene_path;     // "" = the built-in scene
  std::string endpoint_base;  // "" = the default local folder
  Scene scene() const;        // loads (and validates) the scene file, or the built-in scene
  Endpoints endpoints() const;
  bool makes_keys = false;    // the master: creates the farm key when CURVE needs one (setupCurve)
};

// Adds the positional scene (TESSERA_SCENE) and --endpoints (TESSERA_ENDPOINTS); call it
// first: every option added after it shows its default in --help.
void addStageArgs(CLI::App& app, StageArgs& args, const std::string& scene_help);

using StageBody = std::function<int(const Endpoints&, zmq::context_t&, const std::atomic<bool>* stop)>;

// Parses the flags, then runs `body`; returns the process's exit code.
int stageMain(CLI::App& app, int argc, char** argv, const StageArgs& args, const StageBody& body);

}  // namespace tessera
