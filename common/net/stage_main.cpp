#include "common/net/stage_main.h"

#include <sys/resource.h>

#include <spdlog/spdlog.h>

#include "common/net/curve.h"
#include "common/net/stop.h"

namespace tessera {

Scene StageArgs::scene() const { return scene_path.empty() ? defaultScene() : loadScene(scene_path); }

Endpoints StageArgs::endpoints() const {
  return makeEndpoints(endpoint_base.empty() ? defaultEndpointBase() : endpoint_base);
}

void addStageArgs(CLI::App& app, StageArgs& args, const std::string& scene_help) {
  app.option_defaults()->always_capture_default();  // every --help shows the defaults
  app.add_option("scene", args.scene_path, scene_help)->envname("TESSERA_SCENE");
  app.add_option("--endpoints", args.endpoint_base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")
      ->envname("TESSERA_ENDPOINTS");
}

int stageMain(CLI::App& app, int argc, char** argv, const StageArgs& args, const StageBody& body) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  int rc = 1;
  try {
    const Endpoints endpoints = args.endpoints();
    zmq::context_t ctx(1);
    setupCurve(ctx, endpoints.base, args.makes_keys);  // on when endpoints leave this host
    rc = body(endpoints, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
  }
  removeBoundIpcFiles();
  // What a process needed is what a cluster must give it: said by every stage at exit.
  rusage ru{};
  if (getrusage(RUSAGE_SELF, &ru) == 0) spdlog::info("peak memory {:.1f} MiB", (double)ru.ru_maxrss / 1024);
  return rc;
}

}  // namespace tessera
