// The master under hostile or broken peers, in one process over ipc:// in a temporary
// folder: junk frames cannot hang it, strangers cannot report work, a fixed run ignores
// camera input, a renderer that heartbeats but never delivers is replaced, and a stage
// lost for a while is given work again once it is heard from.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <future>
#include <random>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <spdlog/sinks/ostream_sink.h>

#include "common/net/stage_link.h"
#include "common/net/transport.h"
#include "compositor/stage.h"
#include "display/stage.h"
#include "master/master.h"
#include "renderer/stage.h"
#include "renderer/volume/raycaster.h"
#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

using namespace std::chrono_literals;
using proto::Role;

template <class F>
bool waitUntil(F done, std::chrono::milliseconds limit, std::function<void()> meanwhile = [] {}) {
  for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
    if (done()) return true;
    meanwhile();
    std::this_thread::sleep_for(20ms);
  }
  return done();
}

// A stage made of raw sockets, driven by the test thread: joins like StageLink (same
// routing-id form), heartbeats only when told, and delivers nothing.
class FakeStage {
 public:
  FakeStage(zmq::context_t& ctx, const Endpoints& ep, Role role, std::string scene, std::string run = "")
      : role_(role), run_(std::move(run)), scene_(std::move(scene)), sub_(makeSocket(ctx, zmq::socket_type::sub)), ctl_(makeSocket(ctx, zmq::socket_type::dealer)),
        hb_(makeSocket(ctx, zmq::socket_type::dealer)) {
    std::string id(16, 'f');
    id[15] = static_cast<char>('a' + (int)role + std::random_device()() % 16);
    id += 'c';
    ctl_.set(zmq::sockopt::routing_id, id);
    hb_.set(zmq::sockopt::routing_id, StageLink::heartbeatIdentity(id));
    sub_.set(zmq::sockopt::subscribe, "");
    sub_.connect(ep.masterPub());
    ctl_.connect(ep.masterControl());
    hb_.connect(ep.masterControl());
  }
  bool join(std::chrono::milliseconds limit) {
    zmq::message_t m;
    if (!waitUntil([&] { return sub_.recv(m, zmq::recv_flags::dontwait).has_value(); }, limit)) return false;
    sendBytes(ctl_, proto::encode(proto::Hello{role_, 4242, "", run_, scene_}, 0));
    return waitUntil([&] {
      if (!ctl_.recv(m, zmq::recv_flags::dontwait)) return false;
      if (auto refused = proto::decodeShutdown(view(m))) refusal_ = refused->reason;
      auto w = proto::decodeWelcome(view(m));
      if (w) rank_ = w->rank;
      return (bool)w || !refusal_.empty();
    }, limit) && refusal_.empty();
  }
  const std::string& refusal() const { return refusal_; }  // the master's reason, if it refused
  void heartbeat() { sendBytes(hb_, proto::encode(proto::Heartbeat{role_, rank_}, rank_), false, true); }
  void report(std::vector<std::byte>&& bytes) { sendBytes(ctl_, std::move(bytes), false, true); }
  std::vector<proto::FrameParams> drain() {
    std::vector<proto::FrameParams> out;
    for (zmq::message_t m; sub_.recv(m, zmq::recv_flags::dontwait);)
      if (auto p = proto::decodeFrameParams(view(m))) out.push_back(*p);
    return out;
  }
  uint32_t rank() const { return rank_; }

 private:
  Role role_;
  std::string run_, scene_, refusal_;
  zmq::socket_t sub_, ctl_, hb_;
  uint32_t rank_ = 0;
};

// The master and any real stages, in threads; stop() ends them, and a master stuck in a
// blocking call is freed by shutting the context down (so a failing test cannot hang).
class Farm {
 public:
  explicit Farm(const std::string& name, Scene scene)
      : dir_(name), scene_(std::move(scene)), ep_(makeEndpoints("ipc://" + (dir_.path() / "sockets").string())) {
    fs::create_directories(dir_.path() / "sockets");
    mo_.scene = scene_;
    mo_.endpoints = ep_;
    mo_.metrics_path = (dir_.path() / "metrics.jsonl").string();
    co_.scene = do_.scene = sceneIdentity(scene_);
  }
  ~Farm() { stop(); }
  master::MasterOptions& options() { return mo_; }
  void startMaster() {
    master_ = std::async(std::launch::async, [this] { return master::run(mo_, ctx_, &stop_); });
  }
  void startStages(int renderers, bool compositor = true, bool display = true) {
    for (int i = 0; i < renderers; ++i)
      stages_.push_back(std::async(std::launch::async, [this] { return renderer::runStage(ro_, ctx_, &stop_); }));
    if (compositor) stages_.push_back(std::async(std::launch::async, [this] { return compositor::runStage(co_, ctx_, &stop_); }));
    if (display) stages_.push_back(std::async(std::launch::async, [this] { return display::runStage(do_, ctx_, &stop_); }));
  }
  bool masterDone() { return master_.wait_for(0s) == std::future_status::ready; }
  // The master's exit code, or -1 if it had to be freed.
  int stop() {
    if (!master_.valid()) return -1;
    stop_ = true;
    bool freed = master_.wait_for(15s) != std::future_status::ready;
    if (freed) ctx_.shutdown();
    int rc = -1;
    try {
      rc = master_.get();
    } catch (const std::exception&) {
    }
    for (auto& s : stages_) try { s.get(); } catch (const std::exception&) {}
    return freed ? -1 : rc;
  }
  int join(std::chrono::seconds limit, std::function<void()> meanwhile = [] {}) {
    if (!waitUntil([&] { return masterDone(); }, limit, meanwhile)) return -2;
    return stop();
  }
  zmq::context_t& ctx() { return ctx_; }
  const Endpoints& endpoints() const { return ep_; }
  FarmDir& dir() { return dir_; }
  const Scene& scene() const { return scene_; }
  std::vector<nlohmann::json> metrics() const {
    std::vector<nlohmann::json> out;
    std::ifstream in(dir_.path() / "metrics.jsonl");
    for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
    return out;
  }

 private:
  FarmDir dir_;
  Scene scene_;
  Endpoints ep_;
  zmq::context_t ctx_;
  std::atomic<bool> stop_{false};
  master::MasterOptions mo_;
  renderer::StageOptions ro_{scene_, ep_, 1};
  compositor::StageOptions co_{ep_, "", 512, 512, std::nullopt};
  display::StageOptions do_{ep_, (dir_.path() / "out").string(), display::StageOptions::Window::Off, std::nullopt};
  std::future<int> master_;
  std::vector<std::future<int>> stages_;
};

// Every frame 0..frames-1 written and within 1/255 of the one-process orbit render.
void expectOrbitFrames(Farm& farm, int frames) {
  const Scene& scene = farm.scene();
  auto volume = std::make_shared<Volume>(loadVolume(scene));
  renderer::Raycaster caster(volume, scene.tf);
  renderer::RenderOptions opt;
  opt.quality = scene.quality;
  for (int k = 0; k < frames; ++k) {
    ASSERT_TRUE(fs::exists(farm.dir().frame(k))) << "frame " << k << " missing";
    Image8 ref = toRGBA8(caster.render(scene.orbit.at(scene.camera, k), scene.width, scene.height,
                                       renderer::wholeVolume(*volume), opt));
    EXPECT_TRUE(farm.dir().matches(readPng(farm.dir().frame(k).string()), ref, 1, "frame_" + std::to_string(k)));
  }
}

std::vector<std::byte> randomBytes(std::mt19937& rng, size_t n) {
  std::vector<std::byte> b(n);
  for (auto& x : b) x = static_cast<std::byte>(rng() & 0xFF);
  return b;
}

TEST(MasterRobustness, MultipartAndRandomBytesDoNotHangTheMaster) {
  Farm farm("multipart", smallScene(4));
  farm.startMaster();
  {
    zmq::socket_t junk(farm.ctx(), zmq::socket_type::dealer);
    junk.set(zmq::sockopt::linger, 1000);
    junk.connect(farm.endpoints().masterControl());
    std::mt19937 rng(7);
    auto hello = proto::encode(proto::Hello{Role::Renderer, 1, "", ""}, 0);
    junk.send(zmq::buffer(hello.data(), hello.size()), zmq::send_flags::sndmore);
    junk.send(zmq::str_buffer("trailing frame"), zmq::send_flags::none);
    for (int i = 0; i < 20; ++i) {
      auto a = randomBytes(rng, 1 + rng() % 200), b = randomBytes(rng, rng() % 50);
      junk.send(zmq::buffer(a.data(), a.size()), i % 2 ? zmq::send_flags::sndmore : zmq::send_flags::none);
      if (i % 2) junk.send(zmq::buffer(b.data(), b.size()), zmq::send_flags::none);
    }
  }
  FakeStage stage(farm.ctx(), farm.endpoints(), Role::Compositor, sceneIdentity(farm.scene()));
  EXPECT_TRUE(stage.join(10s)) << "the master did not answer a real Hello after junk";
  EXPECT_NE(farm.stop(), -1) << "the master had to be freed from a blocking call";  // 1: stopped while gathering
}

TEST(MasterRobustness, ReportsFromStrangersAreRefusedAndCounted) {
  const int frames = 24;
  Farm farm("forged", smallScene(frames));
  farm.startMaster();
  // Connect once the master listens (an ipc connect before the bind retries only after 100 ms,
  // and this farm can be done by then).
  const std::string control = farm.endpoints().masterControl();
  ASSERT_TRUE(waitUntil([&] { return fs::exists(control.substr(6)); }, 10s)) << control;
  zmq::socket_t stranger(farm.ctx(), zmq::socket_type::dealer);
  stranger.set(zmq::sockopt::linger, 0);
  stranger.set(zmq::sockopt::sndtimeo, 2000);  // wait (bounded) for the connection, never drop silently
  stranger.connect(control);
  auto forge = [&] {  // FrameDone for every frame, and Stats claiming to be renderer 0
    for (uint64_t f = 0; f < frames; ++f) {
      proto::FrameDone d;
      d.frame = f;
      sendBytes(stranger, proto::encode(d, 0));
      proto::StageStats s;
      s.frame = f;
      sendBytes(stranger, proto::encode(s, 0));
    }
  };
  forge();  // before the stages join: the master reads these while it gathers its members
  farm.startStages(1);
  EXPECT_EQ(farm.join(60s, forge), 0);
  expectOrbitFrames(farm, frames);
  auto lines = farm.metrics();
  ASSERT_EQ(lines.size(), (size_t)frames);
  EXPECT_GT(lines.back()["refused_peers"].get<uint64_t>(), 0u);
}

TEST(MasterRobustness, AStageOfAnotherRunIsRefusedToldWhyAndCounted) {
  const int frames = 30;
  Farm farm("other-run", smallScene(frames));
  farm.options().run = "farm-b";
  farm.startMaster();
  FakeStage stranger(farm.ctx(), farm.endpoints(), Role::Renderer, sceneIdentity(farm.scene()), "farm-a");
  EXPECT_FALSE(stranger.join(10s)) << "a renderer of run farm-a joined farm-b";
  EXPECT_NE(stranger.refusal().find("this farm is run 'farm-b'"), std::string::npos) << stranger.refusal();
  EXPECT_NE(stranger.refusal().find("of run 'farm-a'"), std::string::npos) << stranger.refusal();
  // The farm's own stages (run "" here, as the master's option is set only for the master)
  // would be refused too: give them the master's run through the environment they read.
  setenv("TESSERA_RUN", "farm-b", 1);
  farm.startStages(1);
  EXPECT_EQ(farm.join(60s), 0);
  unsetenv("TESSERA_RUN");
  expectOrbitFrames(farm, frames);
  auto lines = farm.metrics();
  ASSERT_EQ(lines.size(), (size_t)frames);
  EXPECT_GE(lines.back()["refused_peers"].get<uint64_t>(), 1u);
  for (const auto& p : lines) EXPECT_EQ(p["render_reports"].get<int>(), 1) << "the stranger got work";
}

// Each host reads its own copy of the scene file: a stage whose copy differs (here its image
// size, which bounds what it accepts, and its colour map) would blend or bound pieces
// otherwise than the master plans, so it is refused, told the first line that differs, and
// exits with an error; the farm's own stages render on.
TEST(MasterRobustness, AStageOfAnotherSceneIsRefusedToldWhichLineDiffersAndCounted) {
  const int frames = 20;
  Farm farm("other-scene", smallScene(frames));
  farm.startMaster();
  Scene other = farm.scene();
  other.width += 16;
  FakeStage stranger(farm.ctx(), farm.endpoints(), Role::Compositor, sceneIdentity(other));
  EXPECT_FALSE(stranger.join(10s)) << "a compositor of another scene joined";
  const std::string& why = stranger.refusal();
  EXPECT_NE(why.find("read another scene than the master"), std::string::npos) << why;
  EXPECT_NE(why.find(fmt::format("'image: [{}, {}]' there", other.width, other.height)), std::string::npos) << why;
  EXPECT_NE(why.find(fmt::format("'image: [{}, {}]' here", farm.scene().width, farm.scene().height)), std::string::npos)
      << why;
  // A real stage of another scene (its colour map) is refused the same way and exits with an error.
  Scene other_map = farm.scene();
  other_map.tf = transferFunctionPreset("grayscale");
  ASSERT_NE(sceneIdentity(other_map), sceneIdentity(farm.scene())) << "the test changes nothing";
  renderer::StageOptions ro{other_map, farm.endpoints(), 1};
  auto refused = std::async(std::launch::async, [&] { return renderer::runStage(ro, farm.ctx()); });
  ASSERT_EQ(refused.wait_for(30s), std::future_status::ready) << "a renderer of another scene is still waiting";
  EXPECT_EQ(refused.get(), 1);
  farm.startStages(1);
  EXPECT_EQ(farm.join(60s), 0);
  expectOrbitFrames(farm, frames);
  auto lines = farm.metrics();
  ASSERT_EQ(lines.size(), (size_t)frames);
  EXPECT_GE(lines.back()["refused_peers"].get<uint64_t>(), 2u);
  for (const auto& p : lines) EXPECT_EQ(p["render_reports"].get<int>(), 1) << "the refused renderer got work";
}

TEST(MasterRobustness, InputIsRefusedInAFixedLengthRun) {
  const int frames = 200;
  Farm farm("fixed-input", smallScene(frames));
  farm.startMaster();
  farm.startStages(1);
  ASSERT_TRUE(waitUntil([&] { return fs::exists(farm.dir().frame(0)); }, 30s));
  FakeStage user(farm.ctx(), farm.endpoints(), Role::Display, sceneIdentity(farm.scene()));  // a second, joined display
  ASSERT_TRUE(user.join(10s));
  proto::Input in;
  in.orbit_dx = 40;
  user.report(proto::encode(in, 0));
  bool in_time = !fs::exists(farm.dir().frame(frames - 1));
  EXPECT_EQ(farm.join(120s, [&] { user.heartbeat(); }), 0);
  ASSERT_TRUE(in_time) << "the run ended before the input was sent: the test proves nothing";
  expectOrbitFrames(farm, frames);
}

TEST(MasterRobustness, RendererThatHeartbeatsButNeverDeliversIsReplaced) {
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const int frames = 8;
  Farm farm("silent-renderer", smallScene(frames));
  farm.options().renderers = 2;
  farm.options().deadline = {2.0, 1.0, 8.0};
  farm.startMaster();
  farm.startStages(1);
  FakeStage idle(farm.ctx(), farm.endpoints(), Role::Renderer, sceneIdentity(farm.scene()));
  ASSERT_TRUE(idle.join(30s));
  int rc = farm.join(60s, [&] {
    idle.heartbeat();
    idle.drain();
  });
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_EQ(rc, 0) << "the farm stalled on a renderer that never delivers";
  expectOrbitFrames(farm, frames);
  auto lines = farm.metrics();
  ASSERT_FALSE(lines.empty());
  EXPECT_GE(lines.back()["reassignments"].get<uint64_t>(), 1u);
  EXPECT_GE(lines.back()["reissued_frames"].get<uint64_t>(), 1u);
  std::string text = log.str();
  EXPECT_NE(text.find("frame 0 waits for stats from renderer " + std::to_string(idle.rank()) + " (pid 4242)"),
            std::string::npos) << text;
  EXPECT_NE(text.find("missed its deadline"), std::string::npos) << text;
}

TEST(MasterRobustness, LostStageIsReadmittedWhenHeardFromAgain) {
  Farm farm("readmit", smallScene(50));
  farm.options().heartbeat_timeout_s = 0.5;
  farm.startMaster();
  farm.startStages(0);
  FakeStage r(farm.ctx(), farm.endpoints(), Role::Renderer, sceneIdentity(farm.scene()));
  ASSERT_TRUE(r.join(30s));
  uint32_t first_epoch = ~0u;
  auto hasWork = [&](uint32_t newer_than) {
    for (const auto& p : r.drain())
      for (const auto& b : p.sortLast()->bricks)
        if (b.renderer == r.rank() && (newer_than == ~0u || p.epoch > newer_than)) {
          first_epoch = std::min(first_epoch, p.epoch);
          return true;
        }
    return false;
  };
  ASSERT_TRUE(waitUntil([&] { return hasWork(~0u); }, 30s, [&] { r.heartbeat(); })) << "never given work";
  // Paused: silent past the heartbeat timeout (the master says it is lost).
  std::this_thread::sleep_for(1500ms);
  r.drain();
  // Continued: heartbeats again, and must be given work again under a newer epoch.
  EXPECT_TRUE(waitUntil([&] { return hasWork(first_epoch); }, 10s, [&] { r.heartbeat(); }))
      << "a stage heard from again after being lost got no work";
  farm.stop();
}

}  // namespace
}  // namespace tessera::test
