// The display's web view in a real browser: Debian's chromium, headless, driven by
// tests/web/view.mjs (puppeteer-core; `npm ci` in tests/web, which ./setup.sh test runs).
// The farm runs interactively with the web view on loopback; the page's canvas is read back
// and must be the PNG sink's frame exactly (both composited over the same background).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <future>
#include <regex>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/io/image_io.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;

constexpr const char* kToken = "0123456789abcdef-web-test";
constexpr const char* kBackground = "0.125,0.125,0.14";
const std::array<double, 3> kBg{0.125, 0.125, 0.14};

bool haveBrowser() {
  return fs::exists("/usr/bin/chromium") && fs::exists(TESSERA_SOURCE_DIR "/tests/web/node_modules/puppeteer-core");
}

int freePort() {
  const auto r = runCommand("bash -c 'for i in $(seq 100); do p=$((20000 + RANDOM % 12000)); "
                            "ss -Htln \"sport = :$p\" | grep -q . || { echo $p; exit; }; done'", 10);
  return std::atoi(r.output.c_str());
}

std::vector<nlohmann::json> metricsLines(const FarmDir& dir) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(dir.path() / "out" / "metrics.jsonl");
  for (std::string l; std::getline(in, l);) {
    auto j = nlohmann::json::parse(l, nullptr, false);
    if (!j.is_discarded()) lines.push_back(j);
  }
  return lines;
}

template <class F>
bool waitUntil(F ready, std::chrono::milliseconds limit) {
  for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;
       std::this_thread::sleep_for(50ms))
    if (ready()) return true;
  return false;
}

// An interactive farm (it renders on input, until stopped) with the web view on a free port.
class WebView : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(haveBrowser()) << "chromium or tests/web/node_modules missing: ./setup.sh test installs them";
    port_ = freePort();
    ASSERT_GT(port_, 0);
    scene_ = dir_.path() / "cloud.yaml";  // not symmetric: turning it changes the picture
    std::ofstream(scene_) << "volume:\n  generator: {name: noise-cloud, size: 48, seed: 7}\n"
                          << "transfer_function:\n  - [0.00, 0.6, 0.7, 0.9, 0.0]\n  - [0.03, 0.6, 0.7, 0.9, 0.0]\n"
                          << "  - [0.10, 0.6, 0.7, 0.9, 0.05]\n  - [0.40, 0.9, 0.9, 1.0, 0.2]\n  - [1.00, 1.0, 1.0, 1.0, 0.6]\n"
                          << "camera: {eye: [1.6, 0.8, 1.6], target: [0, 0, 0], up: [0, 1, 0], fov: 30}\n"
                          << "image: [800, 600]\nquality: default\n";  // a lossless frame > 64 KiB: several pieces
    env_ = "--env TESSERA_WEB=127.0.0.1:" + std::to_string(port_) + " --env TESSERA_WEB_TOKEN=" + kToken +
           " --env TESSERA_BACKGROUND=" + kBackground;
    startFarm();
    ASSERT_TRUE(waitUntil([&] { return !metricsLines(dir_).empty(); }, 90s)) << dir_.farmLog();
  }
  void startFarm() {
    farm_ = std::async(std::launch::async, [this] { return dir_.runFarm(scene_, 2, 1, 0, 200, env_); });
  }
  void TearDown() override {
    if (!farm_.valid()) return;
    // Ctrl-C to this farm's tessera-up alone (argv[0]; its command line names this test's
    // folder), not to the `timeout` around it, which would pass on a second one.
    runCommand("pkill -INT -f '^[^ ]*tessera-up .*" + dir_.path().string() + "'", 10);
    if (farm_.wait_for(60s) != std::future_status::ready) ADD_FAILURE() << "the farm did not stop";
    else log_ = farm_.get().output;
  }
  std::string url(bool token = true) const {
    return "http://127.0.0.1:" + std::to_string(port_) + "/" + (token ? std::string("#") + kToken : "");
  }
  // Runs view.mjs; its JSON lines.
  std::vector<nlohmann::json> browse(const std::string& actions, const std::string& page_url = "") {
    const auto r = runCommand("node " TESSERA_SOURCE_DIR "/tests/web/view.mjs '" + (page_url.empty() ? url() : page_url) +
                                  "' " + dir_.path().string() + " " + actions,
                              120);
    std::vector<nlohmann::json> out;
    std::istringstream in(r.output);
    for (std::string l; std::getline(in, l);) {
      auto j = nlohmann::json::parse(l, nullptr, false);
      if (j.is_discarded()) continue;
      if (j.contains("action")) out.push_back(j);
      else if (j.contains("error")) ADD_FAILURE() << "browser: " << l << "\n" << dir_.farmLog();
      else std::cout << "browser " << l << "\n";  // the page's console errors
    }
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }
  // The canvas as the browser read it back (opaque RGBA).
  Image8 pagePixels(const std::string& name, const nlohmann::json& meta) const {
    Image8 img(meta["width"].get<int>(), meta["height"].get<int>());
    std::ifstream in(dir_.path() / (name + ".rgba"), std::ios::binary);
    in.read(reinterpret_cast<char*>(img.px.data()), (std::streamsize)img.px.size());
    return img;
  }
  // The PNG sink's frame `id` (composited over the background: opaque).
  Image8 pngFrame(uint64_t id) const {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06llu.png", (unsigned long long)id);
    return readPng((dir_.path() / "out" / name).string());
  }

  FarmDir dir_{"web"};
  int port_ = 0;
  std::string env_;
  fs::path scene_;
  std::future<CommandResult> farm_;
  std::string log_;
};

TEST_F(WebView, TheLosslessFrameOnThePageIsThePngSinksFrameExactly) {
  const auto out = browse("wait-lossless:0 pixels:first shot:web-view");
  ASSERT_EQ(out.size(), 3u);
  EXPECT_GT(out[0]["state"]["log"].back()["bytes"].get<int>(), 64 * 1024) << "the frame went out in several pieces";
  const auto& meta = out[1];
  EXPECT_EQ(meta["kind"], "lossless");
  const uint64_t id = meta["id"].get<uint64_t>();
  const Image8 page = pagePixels("first", meta);
  const Image8 png = pngFrame(id);
  EXPECT_TRUE(dir_.matches(page, png, 0, "page_vs_png_sink"));
  // And the PNG sink's frame is the farm's: the farm's premultiplied frame (the .pam beside
  // the PNG) composited over the background is that PNG exactly, and is within 1/255 of
  // tessera-render's. (Compared after compositing, two frames within 1/255 can differ by 2:
  // one level of colour plus one of alpha times the background.)
  char pam[32];
  std::snprintf(pam, sizeof pam, "frame_%06llu.pam", (unsigned long long)id);
  Image8 farm = readPam((dir_.path() / "out" / pam).string());
  EXPECT_TRUE(dir_.matches(farm, dir_.reference(scene_, 0), 1, "farm_vs_tessera_render"));
  const std::vector<uint8_t> over = pngPixels(farm, kBg);
  std::copy(over.begin(), over.end(), farm.px.begin());
  EXPECT_TRUE(dir_.matches(farm, png, 0, "farm_over_background_vs_png_sink"));
  EXPECT_TRUE(fs::exists(dir_.path() / "web-view.png"));
}

// The right button's drag sets the colour window, not the camera: the picture changes, and the
// final frame is the PNG sink's, with the scene's camera and a window other than the scene's.
TEST_F(WebView, ARightDragSetsTheColourWindow) {
  const auto out = browse("wait-lossless:0 pixels:before right-drag:20 wait-lossless:+ sleep:600 pixels:after state");
  ASSERT_EQ(out.size(), 7u);
  // The status line says which values the colour map now spans (a generated volume's: 0..1 is its range).
  const std::string status = out[6]["state"]["status"].get<std::string>();
  EXPECT_NE(status.find("  colours "), std::string::npos) << status;
  const Image8 before = pagePixels("before", out[1]), after = pagePixels("after", out[5]);
  EXPECT_GT(maxAbsDiff(before, after), 16) << "the right drag did not change the picture";
  const auto lines = metricsLines(dir_);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines.back()["camera"], lines.front()["camera"]) << "the right drag moved the camera";
  EXPECT_EQ(lines.front()["window"], nlohmann::json::array({0.5, 1.0}));
  EXPECT_NE(lines.back()["window"], lines.front()["window"]);
  const uint64_t id = out[5]["id"].get<uint64_t>();
  EXPECT_EQ(id, lines.back()["frame"].get<uint64_t>());
  EXPECT_TRUE(dir_.matches(after, pngFrame(id), 0, "final_page_vs_png_sink"));
}

TEST_F(WebView, ADragChangesThePictureAndEndsOnTheLosslessFrameOfTheFinalCamera) {
  const auto out = browse("wait-lossless:0 pixels:before drag:30 wait-lossless:+ sleep:600 pixels:after state");
  ASSERT_EQ(out.size(), 7u);
  // The page showed moving (JPEG) frames, and never an older frame after a newer one.
  int jpeg = 0;
  int64_t last = -1;
  for (const auto& f : out[6]["state"]["log"]) {
    jpeg += f["kind"] == "jpeg";
    EXPECT_GT(f["id"].get<int64_t>(), last) << "frames out of order on the page";
    last = f["id"].get<int64_t>();
  }
  EXPECT_GE(jpeg, 1) << "no moving frame reached the page";
  const Image8 before = pagePixels("before", out[1]);
  const Image8 after = pagePixels("after", out[5]);
  EXPECT_EQ(out[5]["kind"], "lossless");
  EXPECT_GT(maxAbsDiff(before, after), 16) << "the drag did not change the picture";
  const uint64_t id = out[5]["id"].get<uint64_t>();
  const auto lines = metricsLines(dir_);
  int moving = 0;
  nlohmann::json shown;
  for (const auto& l : lines) {
    moving += l["interactive"].get<bool>();
    if (l["frame"].get<uint64_t>() == id) shown = l;
  }
  EXPECT_GE(moving, 1) << "no frame while the camera moved";
  ASSERT_FALSE(shown.is_null()) << "no metrics for frame " << id;
  EXPECT_FALSE(shown["interactive"].get<bool>());
  EXPECT_EQ(id, lines.back()["frame"].get<uint64_t>()) << "the page must end on the newest frame";
  EXPECT_TRUE(dir_.matches(after, pngFrame(id), 0, "final_page_vs_png_sink"));
}

TEST_F(WebView, FourViewersAtOnceAllFollowTheOneWhoSteers) {
  const auto out = browse("wait-lossless:0 extra:3 drag:20 wait-lossless:+ extras-same");
  ASSERT_EQ(out.size(), 5u);
  EXPECT_EQ(out[1]["viewers"], 4);
  EXPECT_GT(out[4]["id"].get<int>(), 0) << "the drag made new frames";
  for (const auto& id : out[4]["ids"]) EXPECT_EQ(id, out[4]["id"]) << "every viewer ends on the steered frame";
}

TEST_F(WebView, AReloadOrADroppedConnectionShowsTheCurrentFrameWithinASecond) {
  const auto out = browse("wait-lossless:0 reload drop reload drop");
  ASSERT_EQ(out.size(), 5u);
  for (int k : {1, 2, 3, 4}) {
    EXPECT_LT(out[k]["ms"].get<int>(), 1000) << out[k].dump();
    EXPECT_EQ(out[k]["state"]["kind"], "lossless");
  }
}

// A restarted display numbers its frames from 0 again: the open page reconnects by itself and
// shows the new display's frames, though their ids are below those it showed before.
TEST_F(WebView, APageReconnectsToARestartedDisplayAndShowsItsFramesFromZero) {
  auto page = std::async(std::launch::async, [&] {
    return browse("wait-lossless:0 drag:20 wait-lossless:+ signal:restart-now wait-reconnect pixels:after");
  });
  ASSERT_TRUE(waitUntil([&] { return fs::exists(dir_.path() / "restart-now"); }, 90s)) << "the page never got ready";
  TearDown();  // the display stops with its farm...
  startFarm();  // ...and a new farm's display listens on the same port
  const auto out = page.get();
  ASSERT_EQ(out.size(), 6u);
  const int64_t before = out[2]["state"]["shown"].get<int64_t>();
  const int64_t after = out[4]["state"]["shown"].get<int64_t>();
  EXPECT_GT(before, 0) << "the drag made new frames";
  EXPECT_EQ(out[4]["state"]["connects"], 2);
  EXPECT_LT(after, before) << "the new display's frames are numbered from 0";
  EXPECT_TRUE(dir_.matches(pagePixels("after", out[5]), pngFrame((uint64_t)after), 0, "restarted_page_vs_png_sink"));
}

TEST_F(WebView, WithoutTheTokenThePageGetsNoFrameAndTheRefusalIsCounted) {
  // A page opened without the token says so and does not try; any other client is refused.
  auto out = browse("sleep:500", url(false));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0]["state"]["frames"], 0);
  const auto r = runCommand("curl -s -o /dev/null -w '%{http_code}' -H 'Connection: Upgrade' -H 'Upgrade: websocket' "
                            "-H 'Sec-WebSocket-Version: 13' -H 'Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==' "
                            "http://127.0.0.1:" + std::to_string(port_) + "/ws",
                            10);
  EXPECT_NE(r.output, "101") << "a WebSocket without the token was accepted";
  out = browse("sleep:1500", "http://127.0.0.1:" + std::to_string(port_) + "/#wrong-token");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0]["state"]["frames"], 0);
  out = browse("wait-lossless:0");  // the farm still serves a viewer with the token
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0]["state"]["kind"], "lossless");
  TearDown();
  farm_ = {};
  EXPECT_NE(log_.find("web view: refused a connection without the token"), std::string::npos) << log_;
  EXPECT_NE(log_.find("web view: refused a wrong token"), std::string::npos) << log_;
  EXPECT_TRUE(std::regex_search(log_, std::regex("[1-9][0-9]* refused"))) << log_;
}

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

TEST_F(WebView, BadInputIsRefusedCountedAndEveryOtherViewerKeepsItsFrames) {
  const std::string base = "http://127.0.0.1:" + std::to_string(port_);
  // Paths outside the page's folder (dot segments inside it resolve, as URLs do), a POST,
  // and random bytes on the port.
  for (const char* path : {"/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/..%2f..%2fetc/passwd", "/etc/passwd"}) {
    const auto r = runCommand("curl -s --path-as-is -o /dev/null -w '%{http_code}' '" + base + path + "'", 10);
    EXPECT_TRUE(r.output == "404" || r.output == "400") << path << ": " << r.output;
  }
  EXPECT_EQ(runCommand("curl -s -o /dev/null -w '%{http_code}' -X POST -d x " + base + "/", 10).output, "404");
  runCommand("bash -c 'head -c 4096 /dev/urandom > /dev/tcp/127.0.0.1/" + std::to_string(port_) + "'", 10);
  const auto out = browse("wait-lossless:0 bad-ws wait-lossless:0 drag:10 wait-lossless:1");
  ASSERT_EQ(out.size(), 5u);
  EXPECT_TRUE(out[1]["closed_by_display"].get<bool>()) << "the oversized message must close its connection";
  EXPECT_EQ(out[4]["state"]["kind"], "lossless") << "the viewer still steers the farm";
  TearDown();
  farm_ = {};
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log_, m, std::regex("([0-9]+) bad messages, ([0-9]+) bad requests"))) << log_;
  EXPECT_GE(std::stoi(m[1]), 6) << "not JSON, unknown type, bad values, unknown key, binary, oversized";
  EXPECT_GE(std::stoi(m[2]), 5) << "four paths, a POST (random bytes may count as well)";
  EXPECT_NE(log_.find("refused a viewer message: a message that is not JSON"), std::string::npos) << log_;
  EXPECT_NE(log_.find("refused a viewer message: an unknown message type"), std::string::npos) << log_;
  EXPECT_NE(log_.find("refused a viewer message: an unknown key"), std::string::npos) << log_;  // found by review
}

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

// A viewer that connects and never reads, acknowledges or answers a ping: it is sent 2 frames,
// then every newer frame replaces the one it would get next, and after 10 s without an answer
// to the display's pings it is closed; the farm's orbit is not held up and the display's
// memory stays below what even a fifth of the frames queued would take.
TEST(WebViewOrbit, AStalledViewerNeitherHoldsUpTheFarmNorGrowsTheDisplay) {
  FarmDir dir("web-stalled");
  const int frames = 40;  // about 30 s on 2 cores: long after the stalled viewer is closed
  const fs::path scene = dir.writeScene(frames, 48, 1024, 1024);  // 4 MiB a frame: 40 queued would be 160
  const int port = freePort();
  ASSERT_GT(port, 0);
  std::ofstream(dir.path() / "stalled.sh")
      << "for i in $(seq 200); do exec 3<>/dev/tcp/127.0.0.1/" << port << " 2>/dev/null && break; sleep 0.05; done\n"
      << "printf 'GET /ws?token=" << kToken << " HTTP/1.1\\r\\nHost: x\\r\\nUpgrade: websocket\\r\\nConnection: Upgrade\\r\\n"
      << "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\\r\\nSec-WebSocket-Version: 13\\r\\n\\r\\n' >&3\nsleep 60\n";
  auto stalled = std::async(std::launch::async, [&] { return runCommand("bash " + (dir.path() / "stalled.sh").string(), 70); });
  const auto r = dir.runFarm(scene, 2, 1, frames, 120,
                             "--env TESSERA_WEB=127.0.0.1:" + std::to_string(port) + " --env TESSERA_WEB_TOKEN=" + kToken +
                                 " --env TESSERA_IN_FLIGHT=1");
  runCommand("pkill -f 'bash " + (dir.path() / "stalled.sh").string() + "'", 10);
  stalled.wait();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(metricsLines(dir).size(), size_t(frames)) << "every frame of the orbit";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("web view: ([0-9]+) connections, ([0-9]+) frames sent, ([0-9]+) "
                                                         "replaced before sending")))
      << r.output;
  EXPECT_EQ(m[1], "1");
  EXPECT_EQ(std::stoi(m[2]), 2) << "2 frames unacknowledged at most";
  EXPECT_GE(std::stoi(m[3]), 5) << "newer frames replace unsent ones";
  const size_t left = r.output.find("web view: a viewer left (0 watching)"), done = r.output.find("display done");
  EXPECT_LT(left, done) << "the stalled viewer is closed while the farm runs";
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("display \\| .* peak memory ([0-9.]+) MiB"))) << r.output;
  EXPECT_LT(std::stod(m[1]), 64.0) << "the display's peak memory";
}

}  // namespace
}  // namespace tessera::test
