// tessera-master: loads the scene, registers the stages and drives the frames.
#include <CLI/CLI.hpp>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/net/stop.h"
#include "master/master.h"

int main(int argc, char** argv) {
  using namespace tessera;
  auto log = setupLogging("master");
  CLI::App app{"Tessera master: drives frames through the render farm"};
  std::string scene_path, codec = "lzo", format = "rgba16f", base;
  master::MasterOptions opt;
  app.add_option("scene", scene_path, "scene file (default: the built-in scene)")->envname("TESSERA_SCENE");
  app.add_option("--renderers", opt.renderers, "renderers to wait for")->envname("TESSERA_RENDERERS")->check(CLI::Range(1, 1024));
  app.add_option("--compositors", opt.compositors, "compositors to wait for")->envname("TESSERA_COMPOSITORS")->check(CLI::Range(1, 256));
  app.add_option("--frames", opt.frames, "frames to render (-1: the scene's orbit; 0: interactive)")->envname("TESSERA_FRAMES");
  app.add_option("--in-flight", opt.in_flight, "frames in flight")->envname("TESSERA_IN_FLIGHT")->check(CLI::Range(1, 64));
  app.add_option("--codec", codec, "none | lzo | lz4 | zstd")->envname("TESSERA_CODEC");
  app.add_option("--format", format, "pixel format of pieces: rgba16f (default, within 1/255) | rgba8 | rgba32f")->envname("TESSERA_FORMAT");
  app.add_option("--metrics", opt.metrics_path, "JSON-lines metrics file")->envname("TESSERA_METRICS");
  app.add_option("--endpoints", base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")->envname("TESSERA_ENDPOINTS");
  app.add_option("--heartbeat-timeout", opt.heartbeat_timeout_s, "seconds of silence before a stage counts as lost");
  std::string tiling = "balanced";
  app.add_option("--tiling", tiling,
                 "balanced: re-split work every frame from the last frame's measurements (sort-last: compositor "
                 "regions by active pixels; sort-first: tiles by render cost); static: equal splits")
      ->check(CLI::IsMember({"balanced", "static"}));
  app.add_option("--tiles-per-renderer", opt.tiles_per_renderer, "sort-first: tiles per renderer")
      ->check(CLI::Range(1, 64));
  CLI11_PARSE(app, argc, argv);
  try {
    opt.scene = scene_path.empty() ? defaultScene() : loadScene(scene_path);
    // Each brick ends its rays on its own: below this the farm could not match tessera-render.
    if (std::string why = farmAccuracyProblem(opt.scene.quality, opt.renderers); !why.empty())
      throw std::invalid_argument((scene_path.empty() ? std::string("built-in scene") : scene_path) + ": " + why);
    opt.endpoints = makeEndpoints(base.empty() ? defaultEndpointBase() : base);
    opt.codec = parseCodec(codec);
    opt.format = format == "rgba8"     ? proto::PixelFormat::RGBA8
                 : format == "rgba16f" ? proto::PixelFormat::RGBA16F
                 : format == "rgba32f" ? proto::PixelFormat::RGBA32F
                                       : throw std::invalid_argument("--format: expected rgba8, rgba16f or rgba32f");
    opt.balance = tiling == "balanced";
    zmq::context_t ctx(1);
    setupCurve(ctx, opt.endpoints.base);  // on when endpoints leave this host
    return master::run(opt, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}
