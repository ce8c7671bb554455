// tessera-interaction-bench: the window as a user drags in it. Runs the real farm (tessera-up
// on compose.yaml, interactive) with its window on a private Xvfb, drags the mouse across it
// through XTEST at 60 events a second, releases, and reads the master's metrics: frames per
// second during the drag, input-to-present time (median, 95th percentile; the display
// measures it from the event reaching its loop to the frame on screen), and the time from the
// release to the sharp frame against that frame's own issue-to-display time. One run per
// image size and frames-in-flight setting; writes interaction.csv and prints a table.
// With --web, each round also drags in the web view (chromium, tests/web/bench.mjs) on the
// same farm; run under tests/web/viewer_link.sh RATE, the browser is on its own emulated host
// behind a link of that rate. A benchmark, not a timed test.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/io/image_io.h"
#include "tests/display/xvfb.h"
#include "tests/display/xtest.h"  // last: Xlib's macros

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using tessera::display::testing::XUser;

namespace {

struct Result {
  int image = 0, in_flight = 0, round = 0, drag_frames = 0;
  double fps = 0, input_median = 0, input_p95 = 0, sharp_ms = 0, full_ms = 0;
  std::string widths;  // the interactive frames' widths (the rungs chosen)
  nlohmann::json web;  // --web: what the page measured during the same kind of drag
  double farm_fps_web = 0;  // --web: the farm's frames per second during the page's drag
  double fps_watched = 0;   // --web: the window's drag while a page watches (does not steer)
  nlohmann::json watch;     // --web: what that page saw
  std::string lossless_on_page;  // --web: the display's figure for the whole run (median / max ms)
};

// Where the web view listens and the browser runs: loopback, or the viewer's emulated host
// (tests/web/viewer_link.sh).
std::string webHost() {
  const char* s = std::getenv("TESSERA_VIEWER_SERVER");
  return s && *s ? s : "127.0.0.1";
}

// --idle-page: the page neither decodes nor draws the frames it takes (bench.mjs idle).
bool g_idle_page = false;

// The same drag in the web view (tests/web/bench.mjs in chromium), on the same farm; or, with
// `watch`, a page that only watches until dir/stop-watching appears. Either reports the
// browser's CPU over it (browser_cores).
nlohmann::json dragInPage(int port, double drag_s, const fs::path& dir, bool watch = false) {
  const char* ns = std::getenv("TESSERA_VIEWER_NETNS");
  const std::string cmd = fmt::format("{}node {}/tests/web/bench.mjs 'http://{}:{}/#bench-token' {} {} {} {} 2>&1",
                                      ns && *ns ? fmt::format("ip netns exec {} ", ns) : "", TESSERA_SOURCE_DIR,
                                      webHost(), port, drag_s, dir.string(), watch ? "watch" : "drag",
                                      g_idle_page ? "idle" : "shows");
  std::string out;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[4096];
    while (fgets(buf, sizeof buf, p)) out += buf;
    pclose(p);
  }
  auto j = nlohmann::json::parse(out.substr(0, out.find('\n')), nullptr, false);
  if (j.is_discarded() || j.contains("error")) throw std::runtime_error("the page's drag failed: " + out);
  if (!(j.value("browser_cores", 0.0) > 0)) throw std::runtime_error("the page's drag measured no browser CPU: " + out);
  return j;
}

std::vector<nlohmann::json> lines(const fs::path& metrics) {
  std::vector<nlohmann::json> v;
  std::ifstream in(metrics);
  for (std::string l; std::getline(in, l);)
    if (!l.empty()) v.push_back(nlohmann::json::parse(l));
  return v;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, (size_t)(p * (double)(v.size() - 1) + 0.5))];
}

template <class F>
bool waitUntil(F ok, std::chrono::seconds limit) {
  for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
    if (ok()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

// The window's drag of one round: metrics lines [from, to) are its interactive frames, `sharp`
// the full frame after the release.
void windowStats(Result& r, const std::vector<nlohmann::json>& all, size_t from, size_t to,
                 const std::optional<nlohmann::json>& sharp) {
  std::vector<double> input, done;
  std::vector<int> widths;
  for (size_t i = from; i < to && i < all.size(); ++i) {
    const auto& l = all[i];
    if (!l["interactive"].get<bool>()) continue;
    done.push_back(l["done_ms"].get<double>());
    if (l.contains("input_ms")) input.push_back(l["input_ms"].get<double>());
    widths.push_back(l["width"].get<int>());
  }
  r.drag_frames = (int)done.size();
  if (done.empty()) throw std::runtime_error("no interactive frame: the drag did not reach the window");
  if (done.size() > 1) r.fps = (double)(done.size() - 1) * 1000 / (done.back() - done.front());
  r.input_median = percentile(input, 0.5);
  r.input_p95 = percentile(input, 0.95);
  if (sharp) {
    r.sharp_ms = sharp->value("input_ms", 0.0);
    r.full_ms = (*sharp)["latency_ms"].get<double>();
  }
  std::sort(widths.begin(), widths.end());
  widths.erase(std::unique(widths.begin(), widths.end()), widths.end());
  for (int w : widths) r.widths += (r.widths.empty() ? "" : " ") + std::to_string(w);
}

// The farm's frames per second over metrics lines [from, to) (its interactive frames).
double farmFps(const std::vector<nlohmann::json>& all, size_t from, size_t to) {
  std::vector<double> done;
  for (size_t i = from; i < to && i < all.size(); ++i)
    if (all[i]["interactive"].get<bool>()) done.push_back(all[i]["done_ms"].get<double>());
  return done.size() > 1 ? (double)(done.size() - 1) * 1000 / (done.back() - done.front()) : 0;
}

std::vector<Result> runOne(const fs::path& bin, const fs::path& dir, int image, int in_flight, double drag_s, int web_port,
                           int rounds) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ifstream in(fs::path(TESSERA_SOURCE_DIR) / "scenes" / "default.yaml");
    std::ofstream out(dir / "scene.yaml");
    for (std::string l; std::getline(in, l);) out << (l.rfind("image:", 0) == 0 ? fmt::format("image: [{0}, {0}]", image) : l) << "\n";
  }
  tessera::display::testing::Xvfb xvfb;
  std::string err;
  if (!xvfb.start(err)) throw std::runtime_error(err);
  setenv("DISPLAY", xvfb.display().c_str(), 1);
  const std::string cmd = fmt::format(
      "{}/tessera-up {}/compose.yaml --env TESSERA_SCENE={}/scene.yaml --env TESSERA_FRAMES=0 --env TESSERA_WINDOW=on "
      "--env TESSERA_IN_FLIGHT={} --env TESSERA_OUT={} --env TESSERA_ENDPOINTS=ipc://{}/sockets {} > {}/farm.log 2>&1",
      bin.string(), TESSERA_SOURCE_DIR, dir.string(), in_flight, dir.string(), dir.string(),
      web_port ? fmt::format("--env TESSERA_WEB={}:{} --env TESSERA_WEB_TOKEN=bench-token", webHost(), web_port) : "",
      dir.string());
  auto farm = std::async(std::launch::async, [&] { return std::system(cmd.c_str()); });
  XUser user(xvfb.display());
  std::optional<XUser::Geometry> win;
  const fs::path metrics = dir / "metrics.jsonl";
  if (!waitUntil([&] { return (win = user.find("Tessera")) && !lines(metrics).empty(); }, 120s))
    throw std::runtime_error("the farm's window did not show a frame; see " + (dir / "farm.log").string());
  // What the user sees: the window's pixels during the drag and once it is sharp.
  auto shot = [&](const std::string& name) {
    std::string why;
    tessera::Image8 screen = tessera::display::testing::screenshotRoot(xvfb.display(), why), w(win->width, win->height);
    if (screen.px.empty()) return;
    for (int y = 0; y < w.height; ++y)
      for (int x = 0; x < w.width; ++x) std::copy_n(screen.at(win->x + x, win->y + y), 4, w.at(x, y));
    tessera::writePng((dir / name).string(), w);
  };
  struct Drag { size_t from = 0, to = 0; std::optional<nlohmann::json> sharp; };
  // One drag in the window: the metrics lines of its interactive frames and its sharp frame.
  auto windowDrag = [&](int steps, bool shots) {
    Drag d{lines(metrics).size(), 0, {}};
    // Back and forth a whole number of times, 3 px an event (0.9 degree of orbit): every drag,
    // in the window or the page, turns the camera through the same views and ends where it began.
    const int half = std::max(1, steps / (2 * std::max(1, (int)std::lround(steps / 200.0))));
    const int x0 = win->x + win->width / 8, y0 = win->y + win->height / 2;
    user.press(x0, y0);
    const auto began = std::chrono::steady_clock::now();
    for (int i = 0; i < steps; ++i) {  // 60 events a second on the clock, as the page's drag
      const int p = (i + 1) % (2 * half);
      user.moveTo(x0 + 3 * (p < half ? p : 2 * half - p), y0 + (i % 2));
      std::this_thread::sleep_until(began + (i + 1) * std::chrono::microseconds(16667));
      if (i == steps / 2 && shots) shot("moving.png");
    }
    user.button(1, false);
    waitUntil([&] {
      auto v = lines(metrics);
      for (size_t i = d.from; i < v.size(); ++i)
        if (!v[i]["interactive"].get<bool>()) {
          d.sharp = v[i];
          d.to = i;
          return true;
        }
      return false;
    }, 60s);
    if (!d.sharp) d.to = lines(metrics).size();
    std::this_thread::sleep_for(300ms);
    if (shots) shot("sharp.png");
    return d;
  };
  struct Span { Drag alone, watched; size_t web_from = 0, web_to = 0; nlohmann::json web, watch; };
  std::vector<Span> spans;
  const int steps = (int)(drag_s * 60);
  windowDrag(60, false);  // warms the farm up (its first frames, the refinement's first drag); not kept
  for (int round = 0; round < rounds; ++round) {
    Span sp;
    sp.alone = windowDrag(steps, round == 0);
    if (web_port) {
      // The same drag in the window while a page watches, then a drag in the page.
      fs::remove(dir / "watching");
      fs::remove(dir / "stop-watching");
      auto watcher = std::async(std::launch::async, [&] { return dragInPage(web_port, drag_s, dir, true); });
      if (!waitUntil([&] { return fs::exists(dir / "watching"); }, 60s)) throw std::runtime_error("the watching page did not start");
      sp.watched = windowDrag(steps, false);
      std::ofstream(dir / "stop-watching").flush();
      sp.watch = watcher.get();
      sp.web_from = lines(metrics).size();
      sp.web = dragInPage(web_port, drag_s, dir);
      sp.web_to = lines(metrics).size();
    }
    spans.push_back(sp);
  }
  user.key(XK_Escape);
  farm.wait();
  unsetenv("DISPLAY");

  std::string lossless;  // the display's closing figure for the lossless frames on the page
  {
    std::ifstream log(dir / "farm.log");
    for (std::string l; std::getline(log, l);)
      for (const char* kind : {"lossless", "moving"})
        if (auto at = l.find(std::string(kind) + " frames on the page "); at != std::string::npos)
          lossless += (lossless.empty() ? "" : "; ") + l.substr(at);
  }
  const auto all = lines(metrics);
  std::vector<Result> out;
  for (int round = 0; round < rounds; ++round) {
    const Span& sp = spans[(size_t)round];
    Result r;
    r.image = image;
    r.in_flight = in_flight;
    r.round = round;
    windowStats(r, all, sp.alone.from, sp.alone.to, sp.alone.sharp);
    r.web = sp.web;
    r.watch = sp.watch;
    if (web_port) {
      r.farm_fps_web = farmFps(all, sp.web_from, sp.web_to);
      r.fps_watched = farmFps(all, sp.watched.from, sp.watched.to);
    }
    r.lossless_on_page = lossless;
    out.push_back(r);
  }
  return out;
}

// The page's drags beside the window's, one row per round; web.csv.
void webTable(const std::vector<Result>& results, const fs::path& path) {
  const char* rate = std::getenv("TESSERA_VIEWER_RATE") ? std::getenv("TESSERA_VIEWER_RATE") : "loopback";
  std::ofstream wcsv(path);
  wcsv << "image,in_flight,round,viewer_link,window_fps,window_fps_page_watching,watching_page_fps,page_fps,"
          "farm_fps_page_drag,window_input_ms,page_input_ms,"
          "page_input_ms_p95,page_input_ms_first_quarter,page_input_ms_last_quarter,moving_bytes,lossless_bytes,"
          "window_release_to_sharp_ms,page_release_to_lossless_ms,lossless_on_page_after_display_ms,"
          "page_input_display_share_ms,page_input_page_and_link_ms,browser_cores_watching,browser_cores_steering,"
          "driver_cores_steering,page\n";
  std::printf("\n| image | in flight | round | fps window / window with a page watching / page steering (farm) | "
              "input-to-present median ms, "
              "window / page (p95; first / last quarter) | bytes per moving frame | bytes per lossless frame | release "
              "to sharp ms, window / page | browser CPU, cores: watching / steering (+ driver) |\n"
              "|---|---:|---:|---|---|---:|---:|---|---|\n");
  for (const Result& r : results) {
    const auto& w = r.web;
    auto num = [&](const char* k) { return w.value(k, 0.0); };
    wcsv << fmt::format("{},{},{},{},{:.2f},{:.2f},{:.2f},{:.2f},{:.2f},{:.1f},{:.1f},{:.1f},{:.1f},{:.1f},{},{},{:.1f},"
                        "{:.1f},\"{}\",{:.1f},{:.1f},{:.3f},{:.3f},{:.3f},{}\n",
                        r.image, r.in_flight, r.round, rate, r.fps, r.fps_watched, r.watch.value("fps", 0.0), num("fps"),
                        r.farm_fps_web, r.input_median,
                        num("input_ms_median"), num("input_ms_p95"), num("input_ms_first_quarter"),
                        num("input_ms_last_quarter"), num("moving_bytes_median"), num("lossless_bytes"), r.sharp_ms,
                        num("release_to_lossless_ms"), r.lossless_on_page, num("display_share_ms_median"),
                        num("page_and_link_ms_median"), r.watch.value("browser_cores", 0.0), num("browser_cores"),
                        num("driver_cores"), g_idle_page ? "idle" : "shows");
    std::printf("| %d² | %d | %d | %.1f / %.1f / %.1f (%.1f) | %.0f / %.0f (%.0f; %.0f / %.0f) | %.0f | %.0f | %.0f / %.0f "
                "| %.2f / %.2f (+ %.2f) |\n",
                r.image, r.in_flight, r.round, r.fps, r.fps_watched, num("fps"), r.farm_fps_web, r.input_median,
                num("input_ms_median"),
                num("input_ms_p95"), num("input_ms_first_quarter"), num("input_ms_last_quarter"),
                num("moving_bytes_median"), num("lossless_bytes"), r.sharp_ms, num("release_to_lossless_ms"),
                r.watch.value("browser_cores", 0.0), num("browser_cores"), num("driver_cores"));
  }
  for (const Result& r : results)
    if (r.round == 0)
      std::printf("%d², %d in flight: %s\n", r.image, r.in_flight, r.lossless_on_page.c_str());
  // Where a page's input-to-present goes: in the display (input received to the frame handed
  // to its sinks) and the rest (the input's way to the display, the web view's encoding, the
  // frame's way to the page, the page's paint).
  for (const Result& r : results)
    std::printf("%d², round %d: page input-to-present %.0f ms median = display %.0f + page and link %.0f\n", r.image,
                r.round, r.web.value("input_ms_median", 0.0), r.web.value("display_share_ms_median", 0.0),
                r.web.value("page_and_link_ms_median", 0.0));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tessera-interaction-bench: fps and input-to-present latency while dragging in the farm's window"};
  std::vector<int> images{512, 1024}, in_flight{1, 3};
  int web_port = 0, rounds = 1;
  double drag_s = 5;
  std::string out = "bench-out/interaction";
  app.add_option("--image", images, "image sizes (square)")->capture_default_str();
  app.add_option("--in-flight", in_flight, "frames-in-flight settings")->capture_default_str();
  app.add_option("--drag-seconds", drag_s, "length of the drag")->capture_default_str()->check(CLI::Range(0.5, 120.0));
  app.add_option("--rounds", rounds, "drags per farm (window, then page, in turn)")->capture_default_str()->check(CLI::Range(1, 20));
  app.add_option("--out", out, "folder for the runs and interaction.csv")->capture_default_str();
  app.add_option("--web", web_port, "also serve the web view on this port and drag in it after the window "
                                    "(chromium, tests/web/bench.mjs)");
  app.add_flag("--idle-page", g_idle_page, "with --web: the page takes and acknowledges every frame but neither decodes "
                                          "nor draws it (what the browser costs for a page that shows nothing)");
  CLI11_PARSE(app, argc, argv);
  if (!tessera::display::testing::onPath("Xvfb")) {
    std::fprintf(stderr, "tessera-interaction-bench: Xvfb not installed (apt-get install xvfb)\n");
    return 77;
  }
  const fs::path bin = fs::canonical("/proc/self/exe").parent_path();
  std::vector<Result> results;
  try {
    for (int image : images)
      for (int k : in_flight) {
        std::fprintf(stderr, "image %dx%d, %d in flight: %d rounds of %.1f s drags...\n", image, image, k, rounds, drag_s);
        auto rs = runOne(bin, fs::absolute(out) / fmt::format("{}-{}", image, k), image, k, drag_s, web_port, rounds);
        results.insert(results.end(), rs.begin(), rs.end());
      }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-interaction-bench: %s\n", e.what());
    return 1;
  }
  std::ofstream csv(fs::absolute(out) / "interaction.csv");
  csv << "image,in_flight,round,drag_frames,fps,input_ms_median,input_ms_p95,release_to_sharp_ms,sharp_frame_ms,widths\n";
  std::printf("| image | in flight | round | frames during drag | fps | input-to-present median ms | p95 ms | release to sharp ms "
              "| sharp frame's own ms | ratio | interactive widths |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  for (const Result& r : results) {
    csv << fmt::format("{},{},{},{},{:.2f},{:.1f},{:.1f},{:.1f},{:.1f},{}\n", r.image, r.in_flight, r.round, r.drag_frames,
                       r.fps, r.input_median, r.input_p95, r.sharp_ms, r.full_ms, r.widths);
    std::printf("| %d² | %d | %d | %d | %.1f | %.0f | %.0f | %.0f | %.0f | %.2f | %s |\n", r.image, r.in_flight, r.round,
                r.drag_frames, r.fps, r.input_median, r.input_p95, r.sharp_ms, r.full_ms,
                r.full_ms > 0 ? r.sharp_ms / r.full_ms : 0, r.widths.c_str());
  }
  if (web_port) webTable(results, fs::absolute(out) / "web.csv");
  return 0;
}
