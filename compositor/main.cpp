// tessera-compositor: one compositor stage of the farm (ranks come from the master).
#include "common/net/log.h"
#include "common/net/stage_main.h"
#include "compositor/stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  setupLogging("compositor");
  CLI::App app{"Tessera compositor: composites one screen region of every frame"};
  StageArgs args;
  compositor::StageOptions opt;
  addStageArgs(app, args, "scene file (default: the built-in scene), the master's: its image size and blend are used, and the master refuses a compositor of another scene");
  app.add_option("--advertise-host", opt.advertise_host,
                 "tcp: host renderers use to reach this compositor ('hostname' = this machine's name, 'ip' = its address on the route to the master)")
      ->envname("TESSERA_ADVERTISE_HOST");
  return stageMain(app, argc, argv, args, [&](const Endpoints& endpoints, zmq::context_t& ctx, auto stop) {
    opt.advertise_host = resolveAdvertiseHost(opt.advertise_host, endpoints);
    // Parses the scene only (its volume is never loaded): the image size bounds what
    // peers may send to this stage.
    const Scene parsed = args.scene();
    opt.width = parsed.width;
    opt.height = parsed.height;
    if (isProjection(parsed.blend)) opt.maximum = parsed.tf, opt.minimum = parsed.blend == Blend::Minimum;
    opt.scene = sceneIdentity(parsed);
    opt.endpoints = endpoints;
    return compositor::runStage(opt, ctx, stop);
  });
}
