// tessera-display: shows the farm's frames in a window, or writes them as PNG files.
#include <CLI/CLI.hpp>
#include <map>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/scene.h"
#include "common/net/stop.h"
#include "display/stage.h"

int main(int argc, char** argv) {
  using namespace tessera;
  auto log = setupLogging("display");
  CLI::App app{"Tessera display: presents the farm's frames"};
  std::string base, scene;
  std::vector<double> bg;
  display::StageOptions opt;
  app.add_option("scene", scene, "scene file (default: the built-in scene); only its image size is used")
      ->envname("TESSERA_SCENE");
  app.add_option("--endpoints", base, "endpoint base (ipc://DIR | tcp://HOST:PORT)")->envname("TESSERA_ENDPOINTS");
  app.add_option("--out", opt.out_dir, "folder for PNG frames (no window)")->envname("TESSERA_OUT");
  using Window = display::StageOptions::Window;
  const std::map<std::string, Window> windows{{"auto", Window::Auto}, {"on", Window::On}, {"off", Window::Off}};
  app.add_option("--window", opt.window, "auto | on | off")->envname("TESSERA_WINDOW")
      ->transform(CLI::CheckedTransformer(windows));
  app.add_flag("--premultiplied", opt.premultiplied, "also write frame_NNNNNN.pam: exact premultiplied rgba8")
      ->envname("TESSERA_PREMULTIPLIED");
  app.add_option("--background", bg, "r,g,b in [0,1]: PNGs composited over this colour")->delimiter(',')->expected(3);
  CLI11_PARSE(app, argc, argv);
  try {
    if (!bg.empty()) opt.background = std::array<double, 3>{bg[0], bg[1], bg[2]};
    // Parses the scene only (its volume is never loaded): the image size bounds what
    // peers may send to this stage.
    Scene parsed = scene.empty() ? defaultScene() : loadScene(scene);
    opt.width = parsed.width;
    opt.height = parsed.height;
    opt.endpoints = makeEndpoints(base.empty() ? defaultEndpointBase() : base);
    zmq::context_t ctx(1);
    setupCurve(ctx, opt.endpoints.base);  // on when endpoints leave this host
    return display::runStage(opt, ctx, &installStopSignals());
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}
