// tessera-compositor: one compositor stage of the farm (ranks come from the master).
#include <CLI/CLI.hpp>

#include "common/log.h"
#include "common/stop.h"
#include "stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  auto log = setupLogging("compositor");
  CLI::App app{"Tessera compositor: composites one screen region of every frame"};
  std::string base, scene;
  compositor::StageOptions opt;
  app.add_option("scene", scene, "accepted so every process takes the same arguments; unused");
  app.add_option("--endpoints", base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")->envname("TESSERA_ENDPOINTS");
  app.add_option("--advertise", opt.advertise, "endpoint renderers use to reach this compositor")
      ->envname("TESSERA_ADVERTISE");
  CLI11_PARSE(app, argc, argv);
  try {
    opt.endpoints = makeEndpoints(base.empty() ? defaultEndpointBase() : base);
    zmq::context_t ctx(1);
    return compositor::runStage(opt, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}
