// tessera-renderer: one renderer stage of the farm (ranks come from the master).
#include <CLI/CLI.hpp>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/net/stop.h"
#include "renderer/stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  auto log = setupLogging("renderer");
  CLI::App app{"Tessera renderer: renders its bricks of every frame"};
  std::string scene_path, base;
  renderer::StageOptions opt;
  app.add_option("scene", scene_path, "scene file (default: the built-in scene)")->envname("TESSERA_SCENE");
  app.add_option("--endpoints", base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")->envname("TESSERA_ENDPOINTS");
  app.add_option("--threads", opt.threads, "ray-casting threads (0: all cores)")->envname("TESSERA_THREADS");
  std::string backend = "cpu";
  app.add_option("--backend", backend, "volume backend: cpu (SIMD ray caster) | osmesa (GLSL on llvmpipe)")
      ->envname("TESSERA_BACKEND")
      ->check(CLI::IsMember({"cpu", "osmesa"}));
  CLI11_PARSE(app, argc, argv);
  try {
    opt.backend = renderer::parseBackend(backend);
    opt.scene = scene_path.empty() ? defaultScene() : loadScene(scene_path);
    opt.endpoints = makeEndpoints(base.empty() ? defaultEndpointBase() : base);
    zmq::context_t ctx(1);
    setupCurve(ctx, opt.endpoints.base);  // on when endpoints leave this host
    return renderer::runStage(opt, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}
