// tessera-master: loads the scene, registers the stages and drives the frames.
#include <map>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/net/stage_main.h"
#include "master/master.h"

int main(int argc, char** argv) {
  using namespace tessera;
  setupLogging("master");
  CLI::App app{"Tessera master: drives frames through the render farm"};
  StageArgs args;
  args.makes_keys = true;  // the farm key is the master's: the other stages wait for it
  std::string codec = "lzo";
  master::MasterOptions opt;
  addStageArgs(app, args, "scene file (default: the built-in scene)");
  app.add_option("--renderers", opt.renderers, "renderers to wait for")->envname("TESSERA_RENDERERS")->check(CLI::Range(1, 1024));
  app.add_option("--compositors", opt.compositors, "compositors to wait for")->envname("TESSERA_COMPOSITORS")->check(CLI::Range(0, 256));
  app.add_option("--frames", opt.frames, "frames to render (-1: the scene's orbit; 0: interactive)")->envname("TESSERA_FRAMES");
  app.add_option("--in-flight", opt.in_flight, "frames in flight")->envname("TESSERA_IN_FLIGHT")->check(CLI::Range(1, 64));
  app.add_option("--codec", codec, "none | lzo | lz4 | zstd")->envname("TESSERA_CODEC");
  const std::map<std::string, proto::PixelFormat> formats{
      {"rgba8", proto::PixelFormat::RGBA8}, {"rgba16f", proto::PixelFormat::RGBA16F}, {"rgba32f", proto::PixelFormat::RGBA32F}};
  std::string format = "rgba16f";
  app.add_option("--format", format, "pixel format of pieces: rgba16f (default, within 1/255) | rgba8 | rgba32f (always, for blend: maximum or minimum)")
      ->envname("TESSERA_FORMAT")
      ->check(CLI::IsMember({"rgba8", "rgba16f", "rgba32f"}));
  app.add_option("--metrics", opt.metrics_path, "JSON-lines metrics file")->envname("TESSERA_METRICS");
  app.add_option("--heartbeat-timeout", opt.heartbeat_timeout_s, "seconds of silence before a stage counts as lost");
  std::string compositing = "auto";
  app.add_option("--compositing", compositing,
                 "sort-last: direct-send (every renderer sends each compositor its part) | binary-swap (renderers "
                 "composite among themselves first, any count of them, and send their bands to the display: half the "
                 "bytes on the busiest link, no compositor needed) | auto (binary swap when the farm's endpoints leave this host)")
      ->envname("TESSERA_COMPOSITING")
      ->check(CLI::IsMember({"auto", "direct-send", "binary-swap"}))
      ->capture_default_str();
  std::string tiling = "balanced";
  app.add_option("--tiling", tiling,
                 "balanced: re-split work every frame from the last frame's measurements (sort-last: compositor "
                 "regions by active pixels; sort-first: tiles by render cost); static: equal splits")
      ->check(CLI::IsMember({"balanced", "static"}));
  app.add_option("--tiles-per-renderer", opt.tiles_per_renderer, "sort-first: tiles per renderer")
      ->check(CLI::Range(1, 64));
  return stageMain(app, argc, argv, args, [&](const Endpoints& endpoints, zmq::context_t& ctx, auto stop) {
    opt.scene = args.scene();
    // Each brick ends its rays on its own: below this the farm could not match tessera-render
    // (a projection's rays end only at the volume's largest or smallest value, exactly).
    if (std::string why = farmAccuracyProblem(opt.scene.quality, opt.renderers);
        !why.empty() && opt.scene.blend == Blend::Composite)
      throw std::invalid_argument((args.scene_path.empty() ? std::string("built-in scene") : args.scene_path) + ": " + why);
    if (opt.scene.mesh && opt.scene.antialiasing.method == AaMethod::Fft)
      spdlog::warn("antialiasing fft is a post filter of the whole image, applied by tessera-render; the farm "
                   "renders this scene without it (use msaa or ssaa for identical farm frames)");
    opt.endpoints = endpoints;
    opt.run = farmRun();
    opt.codec = parseCodec(codec);
    opt.format = formats.at(format);
    opt.balance = tiling == "balanced";
    // Bytes count where they cross links; on one host direct send costs a little less CPU.
    opt.binary_swap = compositing == "binary-swap" || (compositing == "auto" && endpointLeavesHost(endpoints.base));
    if (opt.compositors == 0 && (opt.scene.mesh || !opt.binary_swap))
      throw std::invalid_argument(std::string("TESSERA_COMPOSITORS=0: only binary swap (a volume scene, ") +
                                  "TESSERA_COMPOSITING=binary-swap) runs without compositors; this farm " +
                                  (opt.scene.mesh ? "renders a mesh (sort-first)" : "composites by direct send") +
                                  ": give it at least one compositor");
    return master::run(opt, ctx, stop);
  });
}
