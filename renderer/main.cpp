// tessera-renderer: one renderer stage of the farm (ranks come from the master).
#include <malloc.h>

#include "common/net/log.h"
#include "common/net/stage_main.h"
#include "renderer/stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  setupLogging("renderer");
  // Voxel windows (a time series: one per step held) are big and come and go on two threads:
  // a fixed threshold keeps them mmap'ed, so a freed step goes back to the system. glibc's
  // default threshold grows past them after the first free and fragments the heap instead.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
  CLI::App app{"Tessera renderer: renders its bricks of every frame"};
  StageArgs args;
  renderer::StageOptions opt;
  addStageArgs(app, args, "scene file (default: the built-in scene)");
  app.add_option("--threads", opt.threads, "ray-casting threads (0: all cores)")->envname("TESSERA_THREADS");
  app.add_option("--cache-mb", opt.cache_mb, "time series: MiB of voxels held for steps besides the one rendered")
      ->envname("TESSERA_CACHE_MB")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  app.add_option("--advertise-host", opt.advertise_host,
                 "tcp: host the other renderers use to reach this one for binary swap ('hostname', 'ip' = its address on the route to the master)")
      ->envname("TESSERA_ADVERTISE_HOST");
  std::string backend = "cpu";
  app.add_option("--backend", backend, "volume backend: cpu (SIMD ray caster) | osmesa (GLSL on llvmpipe)")
      ->envname("TESSERA_BACKEND")
      ->check(CLI::IsMember({"cpu", "osmesa"}));
  return stageMain(app, argc, argv, args, [&](const Endpoints& endpoints, zmq::context_t& ctx, auto stop) {
    opt.backend = renderer::parseBackend(backend);
    opt.scene = args.scene();
    opt.endpoints = endpoints;
    opt.advertise_host = resolveAdvertiseHost(opt.advertise_host, endpoints);
    return renderer::runStage(opt, ctx, stop);
  });
}
