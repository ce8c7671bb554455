// tessera-display: shows the farm's frames in a window, or writes them as PNG files.
#include <CLI/CLI.hpp>
#include <map>

#include "common/io/image_io.h"
#include "common/net/log.h"
#include "common/net/stage_main.h"
#include "display/stage.h"
#include "display/web_server.h"

int main(int argc, char** argv) {
  using namespace tessera;
  setupLogging("display");
  CLI::App app{"Tessera display: presents the farm's frames"};
  StageArgs args;
  std::vector<double> bg;
  display::StageOptions opt;
  addStageArgs(app, args, "scene file (default: the built-in scene), the master's: its image size is used, and the master refuses a display of another scene");
  app.add_option("--out", opt.out_dir, "folder for PNG frames (no window)")->envname("TESSERA_OUT");
  using Window = display::StageOptions::Window;
  const std::map<std::string, Window> windows{{"auto", Window::Auto}, {"on", Window::On}, {"off", Window::Off}};
  app.add_option("--window", opt.window, "auto (a window if a display server answers, else PNG files) | on | off")
      ->envname("TESSERA_WINDOW")
      ->transform(CLI::CheckedTransformer(windows))
      ->option_text("auto|on|off [auto] (Env:TESSERA_WINDOW)");
  app.add_flag("--premultiplied", opt.premultiplied, "also write frame_NNNNNN.pam: exact premultiplied rgba8")
      ->envname("TESSERA_PREMULTIPLIED");
  app.add_option("--web", opt.web,
                 "HOST:PORT: also serve the web view there (a page and a WebSocket; the log gives the URL "
                 "with the token, TESSERA_WEB_TOKEN or a new one)")
      ->envname("TESSERA_WEB");
  app.add_option("--background", bg, "r,g,b in [0,1]: PNGs (and the web view) composited over this colour")
      ->envname("TESSERA_BACKGROUND")
      ->delimiter(',')
      ->expected(3)
      ->option_text("R,G,B [none: straight alpha]");
  return stageMain(app, argc, argv, args, [&](const Endpoints& endpoints, zmq::context_t& ctx, auto stop) {
    opt.background = backgroundColour(bg);
    // Parses the scene only (its volume is never loaded): the image size bounds what
    // peers may send to this stage.
    const Scene parsed = args.scene();
    opt.width = parsed.width;
    opt.height = parsed.height;
    opt.steps = parsed.series.steps;
    opt.scene = sceneIdentity(parsed);
    opt.endpoints = endpoints;
    opt.web_token = display::webToken();
    return display::runStage(opt, ctx, stop);
  });
}
