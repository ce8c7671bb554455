// tessera-compositor: one compositor stage of the farm (ranks come from the master).
#include <unistd.h>

#include <CLI/CLI.hpp>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/scene.h"
#include "common/net/stop.h"
#include "compositor/stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  auto log = setupLogging("compositor");
  CLI::App app{"Tessera compositor: composites one screen region of every frame"};
  std::string base, scene;
  compositor::StageOptions opt;
  app.add_option("scene", scene, "scene file (default: the built-in scene); only its image size is used")
      ->envname("TESSERA_SCENE");
  app.add_option("--endpoints", base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")->envname("TESSERA_ENDPOINTS");
  app.add_option("--advertise-host", opt.advertise_host,
                 "tcp: host renderers use to reach this compositor ('hostname' = this machine's name, 'ip' = its address on the route to the master)")
      ->envname("TESSERA_ADVERTISE_HOST");
  CLI11_PARSE(app, argc, argv);
  try {
    if (opt.advertise_host == "hostname") {
      char name[256] = {};
      gethostname(name, sizeof name - 1);
      opt.advertise_host = name;
    }
    // Parses the scene only (its volume is never loaded): the image size bounds what
    // peers may send to this stage.
    Scene parsed = scene.empty() ? defaultScene() : loadScene(scene);
    opt.width = parsed.width;
    opt.height = parsed.height;
    opt.endpoints = makeEndpoints(base.empty() ? defaultEndpointBase() : base);
    if (opt.advertise_host == "ip") opt.advertise_host = opt.endpoints.localAddressTowardMaster();
    zmq::context_t ctx(1);
    setupCurve(ctx, opt.endpoints.base);  // on when endpoints leave this host
    return compositor::runStage(opt, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}
