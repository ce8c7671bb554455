#include "master/membership.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/net/stage_link.h"

namespace tessera::master {
namespace {

using namespace std::chrono_literals;
using proto::Role;

const Clock::time_point kStart = Clock::now();
std::string controlId(char c) { return std::string(16, c) + "c"; }

TEST(Membership, RanksPerRoleAndHeartbeatIdentityIsBound) {
  Membership m;
  bool joined = false;
  Member& r0 = m.join(controlId('a'), {Role::Renderer, 11, "", ""}, kStart, &joined);
  EXPECT_TRUE(joined);
  EXPECT_EQ(r0.rank, 0u);
  EXPECT_EQ(m.join(controlId('b'), {Role::Renderer, 12, "", ""}, kStart).rank, 1u);
  EXPECT_EQ(m.join(controlId('d'), {Role::Display, 13, "", ""}, kStart).rank, 0u);
  EXPECT_EQ(m.count(Role::Renderer), 2);
  // The heartbeat connection of renderer 0 belongs to it; it is no control connection.
  std::string hb = StageLink::heartbeatIdentity(controlId('a'));
  ASSERT_EQ(hb, std::string(16, 'a') + "h");
  ASSERT_NE(m.byIdentity(hb), nullptr);
  EXPECT_EQ(m.byIdentity(hb)->pid, 11u);
  EXPECT_EQ(m.byControlIdentity(hb), nullptr);
  EXPECT_EQ(m.byIdentity("stranger"), nullptr);
  EXPECT_EQ(m.display()->pid, 13u);
}

TEST(Membership, SecondHelloOnTheSameConnectionIsTheSameMember) {
  Membership m;
  m.join(controlId('a'), {Role::Renderer, 11, "", ""}, kStart);
  bool joined = true;
  EXPECT_EQ(m.join(controlId('a'), {Role::Renderer, 11, "", ""}, kStart, &joined).rank, 0u);
  EXPECT_FALSE(joined);
  EXPECT_EQ(m.count(Role::Renderer), 1);
}

TEST(Membership, SilentMemberIsLostAndReadmittedWhenHeardAgain) {
  Membership m;
  Member& r = m.join(controlId('a'), {Role::Renderer, 11, "", ""}, kStart);
  m.join(controlId('b'), {Role::Renderer, 12, "", ""}, kStart + 2s);
  auto lost = m.expire(kStart + 3s, 2.0);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0]->pid, 11u);
  EXPECT_EQ(m.count(Role::Renderer), 1);
  // Paused (SIGSTOP), then continued: its next heartbeat brings it back with its rank.
  EXPECT_TRUE(m.heard(r, kStart + 4s));
  EXPECT_TRUE(r.alive);
  EXPECT_EQ(m.count(Role::Renderer), 2);
  EXPECT_FALSE(m.heard(r, kStart + 5s)) << "only the first word re-admits";
}

TEST(Membership, MemberThatMissedADeadlineWaitsOutItsQuarantine) {
  Membership m;
  Member& r = m.join(controlId('a'), {Role::Renderer, 11, "", ""}, kStart);
  m.missedDeadline(r, kStart);
  EXPECT_FALSE(r.alive);
  EXPECT_FALSE(m.heard(r, kStart + 1s)) << "heartbeats alone must not bring back a stage that does not deliver";
  auto q = std::chrono::duration<double>(Membership::quarantineS(1));
  EXPECT_TRUE(m.heard(r, kStart + std::chrono::duration_cast<Clock::duration>(q) + 1ms));
  m.missedDeadline(r, kStart + 10s);
  EXPECT_GT(Membership::quarantineS(2), Membership::quarantineS(1));
  EXPECT_LE(Membership::quarantineS(30), 60.0);
}

TEST(Membership, HeartbeatIdentityOnlyForOurForm) {
  EXPECT_EQ(StageLink::heartbeatIdentity("short"), "");
  EXPECT_EQ(StageLink::heartbeatIdentity(std::string(16, 'x') + "h"), "");
}

// A frame that waits for these renderers' Stats (a binary-swap frame: no compositors).
CreditWindow::Waiting waitingFor(std::vector<uint32_t> renderers) {
  CreditWindow::Waiting w;
  w.renderers = std::move(renderers);
  w.display = w.renderers.empty();
  w.display_sources = Role::Renderer;
  return w;
}

// Binary swap: renderers 0 and 1 await renderer 2's piece of frame 7 (0 through 1), so the
// deadline blames 2, not 0, the first the frame waits for. A wait for another frame, for a
// renderer that already reported, or a cycle of waits leaves the blame where it was.
TEST(Membership, ADeadlineInASwapBlamesTheRendererTheOthersAwait) {
  Membership m;
  Member* r[4];
  for (char c = 0; c < 4; ++c) r[(int)c] = &m.join(controlId('a' + c), {Role::Renderer, 20u + c, "", ""}, kStart);
  r[0]->waiting_frame = 7, r[0]->waiting_for = 1;
  r[1]->waiting_frame = 7, r[1]->waiting_for = 2;
  const Member* culprit = nullptr;
  const std::string who = describeWaiting(m, 7, waitingFor({0, 1, 2}), kStart, &culprit);
  ASSERT_NE(culprit, nullptr);
  EXPECT_EQ(culprit->rank, 2u) << who;
  EXPECT_NE(who.find("renderer 1 awaits renderer 2's swap piece"), std::string::npos) << who;
  describeWaiting(m, 8, waitingFor({0, 1, 2}), kStart, &culprit);
  EXPECT_EQ(culprit->rank, 0u) << "the waits are for frame 7";
  describeWaiting(m, 7, waitingFor({0, 1}), kStart, &culprit);
  EXPECT_EQ(culprit->rank, 1u) << "renderer 2 reported: 1 awaits a piece that was lost, blame stays with 1";
  r[2]->waiting_frame = 7, r[2]->waiting_for = 0;
  describeWaiting(m, 7, waitingFor({0, 1, 2}), kStart, &culprit);
  EXPECT_EQ(culprit->rank, 0u) << "a cycle of waits";
  r[2]->waiting_for = proto::kNobody;
  m.missedDeadline(*r[2], kStart);
  describeWaiting(m, 7, waitingFor({0, 1, 2}), kStart, &culprit);
  EXPECT_EQ(culprit->rank, 1u) << "renderer 2 is already lost";
}

// Every stage reported frame 7 and the display waits: when it says whose strips it lacks (a
// renderer's band in a swap frame, a compositor's region otherwise), that sender is blamed, as
// its strips were lost on the way; without that, the display (whose loss ends the farm).
TEST(Membership, ADeadlineTheDisplayWaitsOutBlamesTheSenderItAwaits) {
  Membership m;
  Member* r[2];
  for (char c = 0; c < 2; ++c) r[(int)c] = &m.join(controlId('a' + c), {Role::Renderer, 20u + c, "", ""}, kStart);
  Member& comp = m.join(controlId('c'), {Role::Compositor, 30, "", ""}, kStart);
  Member& display = m.join(controlId('d'), {Role::Display, 40, "", ""}, kStart);
  const Member* culprit = nullptr;
  std::string who = describeWaiting(m, 7, waitingFor({}), kStart, &culprit);
  ASSERT_NE(culprit, nullptr);
  EXPECT_EQ(culprit->role, Role::Display) << who;
  display.waiting_frame = 7, display.waiting_for = 1;
  who = describeWaiting(m, 7, waitingFor({}), kStart, &culprit);
  EXPECT_EQ(culprit, r[1]) << who;
  EXPECT_NE(who.find("display 0 awaits renderer 1's strips"), std::string::npos) << who;
  CreditWindow::Waiting direct = waitingFor({});
  direct.display_sources = Role::Compositor;
  display.waiting_for = 0;
  describeWaiting(m, 7, direct, kStart, &culprit);
  EXPECT_EQ(culprit, &comp) << "a direct-send frame: compositor 0's strips";
  describeWaiting(m, 8, direct, kStart, &culprit);
  EXPECT_EQ(culprit->role, Role::Display) << "the display awaits frame 7, not 8";
  const Member* named_by = nullptr;
  describeWaiting(m, 7, direct, kStart, &culprit, &named_by);
  EXPECT_EQ(named_by, &display);
  describeWaiting(m, 7, direct, kStart + 2s, &culprit);
  EXPECT_EQ(culprit->role, Role::Display) << "the display's last heartbeat is 2 s old";
  m.missedDeadline(comp, kStart, &display);
  describeWaiting(m, 7, direct, kStart, &culprit);
  EXPECT_EQ(culprit, &comp) << "compositor 0 is already lost: nobody more is dropped, the frame waits for it";
  EXPECT_FALSE(culprit->alive);
  display.waiting_for = 1;
  who = describeWaiting(m, 7, waitingFor({}), kStart + 10s, &culprit);
  EXPECT_EQ(culprit->role, Role::Display) << "naming another sender than the one dropped 10 s before: " << who;
  display.last_seen = kStart + 61s;
  describeWaiting(m, 7, waitingFor({}), kStart + 61s, &culprit);
  EXPECT_EQ(culprit, r[1]) << "a minute later, a new failure";
  m.missedDeadline(display, kStart);
  describeWaiting(m, 7, waitingFor({}), kStart + 61s, &culprit);
  EXPECT_EQ(culprit, nullptr) << "a lost display names nobody";
}

// A direct-send frame whose renderers all reported: compositor 0 waits, and says it lacks
// renderer 1's piece (lost on the way): renderer 1 is blamed, not the compositor.
TEST(Membership, ADeadlineACompositorWaitsOutBlamesTheRendererWhosePieceItLacks) {
  Membership m;
  Member& r1 = (m.join(controlId('a'), {Role::Renderer, 20, "", ""}, kStart),
                m.join(controlId('b'), {Role::Renderer, 21, "", ""}, kStart));
  Member& comp = m.join(controlId('c'), {Role::Compositor, 30, "", ""}, kStart);
  CreditWindow::Waiting w;
  w.compositors = {0};
  const Member* culprit = nullptr;
  describeWaiting(m, 7, w, kStart, &culprit);
  EXPECT_EQ(culprit, &comp);
  comp.waiting_frame = 7, comp.waiting_for = 1;
  const std::string who = describeWaiting(m, 7, w, kStart, &culprit);
  EXPECT_EQ(culprit, &r1) << who;
  EXPECT_NE(who.find("compositor 0 awaits renderer 1's piece"), std::string::npos) << who;
}

// Every host reads its own copy of the scene: what the master sends with each frame (camera,
// quality, orbit) and where a host keeps the files do not count; what a stage renders with does.
TEST(HelloRefusal, AnotherSceneIsNamedByItsFirstDifferingLine) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("tessera-hello-" + std::to_string(getpid()));
  for (const char* f : {"a/head.raw", "a/other.raw", "b/head.raw"}) {
    fs::create_directories((root / f).parent_path());
    std::ofstream(root / f, std::ios::binary) << std::string(512, '\x07');
  }
  const std::string a = (root / "a").string(), b = (root / "b").string();
  const std::string text = "volume: {file: head.raw, dims: [8, 8, 8], type: uint8}\ntransfer_function: viridis\n";
  const Scene master = parseScene(text, a);
  const std::string ours = sceneIdentity(master);
  proto::Hello h{Role::Renderer, 77, "", "run", ours};
  EXPECT_EQ(helloRefusal(h, "run", ours, "ipc:///tmp/farm"), "");
  Scene elsewhere = parseScene(text + "camera: {eye: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0], fov: 20}\nquality: fast\norbit: {frames: 3}\n",
                               b);
  h.scene = sceneIdentity(elsewhere);
  EXPECT_EQ(helloRefusal(h, "run", ours, "ipc:///tmp/farm"), "") << h.scene;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    return t.replace(t.find(from), from.size(), to);
  };
  for (const std::string& other : {replaced("viridis", "grayscale"), replaced("head.raw", "other.raw"),
                                   text + "image: [256, 128]\n", text + "blend: maximum\n", text + "shading: true\n"}) {
    h.scene = sceneIdentity(parseScene(other, a));
    const std::string why = helloRefusal(h, "run", ours, "ipc:///tmp/farm");
    EXPECT_NE(why.find("the renderer (pid 77) read another scene than the master: line "), std::string::npos)
        << other << ": " << why;
  }
  h.scene = sceneIdentity(parseScene(text + "image: [256, 128]\n", a));
  EXPECT_NE(helloRefusal(h, "run", ours, "ipc:///tmp/farm").find("'image: [256, 128]' there and 'image: [512, 512]' here"),
            std::string::npos)
      << helloRefusal(h, "run", ours, "ipc:///tmp/farm");
  h.run = "other";
  EXPECT_NE(helloRefusal(h, "run", ours, "ipc:///tmp/farm").find("this farm is run 'run', the renderer (pid 77) is of run 'other'"),
            std::string::npos);
  fs::remove_all(root);
}

// A long time series is said by its first and last names and a hash of all: a Hello stays
// small (the master takes control messages up to 1 MiB), and any other name still differs.
TEST(HelloRefusal, ALongSeriesIsSaidShortAndStillTold) {
  Scene s = defaultScene();
  RawVolumeSpec raw;
  raw.file = "/a/step_00000.raw", raw.dims = {8, 8, 8};
  s.volume = raw;
  auto steps = [&](const std::string& folder, int renamed) {
    s.series.files.clear();
    for (int k = 0; k < 20000; ++k)
      s.series.files.push_back(fmt::format("{}/step_{:05}{}.raw", folder, k, k == renamed ? "b" : ""));
    s.series.steps = (int)s.series.files.size();
    return sceneIdentity(s);
  };
  const std::string ours = steps("/data/run-1", -1);
  EXPECT_LT(ours.size(), 4096u);
  EXPECT_NE(ours.find("step_00000.raw"), std::string::npos) << ours;
  EXPECT_NE(ours.find("step_19999.raw"), std::string::npos) << ours;
  EXPECT_EQ(steps("/scratch/copy", -1), ours);
  EXPECT_NE(steps("/data/run-1", 12345), ours);
  // Any text too long for a Hello (a colour map of thousands of points) is cut, with a hash of the whole.
  std::vector<TfPoint> points;
  for (int k = 0; k <= 4000; ++k) points.push_back({k / 4000.0, 0.5, 0.5, 0.5, k / 8000.0});
  s.tf = TransferFunction(points);
  const std::string long_map = sceneIdentity(s);
  EXPECT_LT(long_map.size(), 33u * 1024);
  points.back().r = 0.25;
  s.tf = TransferFunction(points);
  EXPECT_NE(sceneIdentity(s), long_map);
}

// A volume file is known by its name and its header (another file of the same name is not
// the same volume), a folder by its own name; a line longer than a message can quote is shown
// where it differs.
TEST(HelloRefusal, FilesByNameAndHeaderAndLongLinesWhereTheyDiffer) {
  Scene s = defaultScene();
  RawVolumeSpec raw;
  raw.file = "/data/a/head.nii.gz", raw.format = VolumeFormat::Nifti, raw.dims = {64, 64, 32};
  raw.type = VoxelType::Int16;
  s.volume = raw;
  const std::string ours = sceneIdentity(s);
  raw.file = "/scratch/head.nii.gz";
  s.volume = raw;
  EXPECT_EQ(sceneIdentity(s), ours);
  raw.dims[2] = 33;
  s.volume = raw;
  proto::Hello h{Role::Compositor, 5, "", "", sceneIdentity(s)};
  EXPECT_NE(helloRefusal(h, "", ours, "ipc:///tmp/farm").find("'header: {dims: [64, 64, 33], type: int16, spacing: [1, 1, 1]}' there"),
            std::string::npos)
      << helloRefusal(h, "", ours, "ipc:///tmp/farm");
  raw.format = VolumeFormat::Dicom, raw.file = "/data/ct/";
  s.volume = raw;
  const std::string folder = sceneIdentity(s);
  raw.file = "/mnt/copy/ct";
  s.volume = raw;
  EXPECT_EQ(sceneIdentity(s), folder);
  h.scene = ours + "extra: 1\n";  // one text longer than the other
  EXPECT_NE(helloRefusal(h, "", ours, "ipc:///tmp/farm").find("is 'extra: 1' there and (none) here"), std::string::npos)
      << helloRefusal(h, "", ours, "ipc:///tmp/farm");
  const std::string a(150, 'a');
  h.scene = "x: 1\n" + a + "Y\n";
  const std::string why = helloRefusal(h, "", "x: 1\n" + a + "X\n", "ipc:///tmp/farm");
  EXPECT_NE(why.find("line 2 "), std::string::npos) << why;
  EXPECT_NE(why.find("'..." + std::string(40, 'a') + "Y' there and '..." + std::string(40, 'a') + "X' here"),
            std::string::npos)
      << why;
}


// An address no peer can connect to (a typo in TESSERA_ADVERTISE_HOST) is refused at the Hello,
// naming it: joined, it would make every healthy partner fail its frames instead.
TEST(AdvertiseRefusal, AnAddressPeersCannotReachIsRefusedAndNamed) {
  proto::Hello h{Role::Renderer, 77, "tcp://10.0.0.5:40123", "run", ""};
  const std::string tcp = "tcp://127.0.0.1:5550", ipc = "ipc:///tmp/farm";
  EXPECT_EQ(advertiseRefusal(h, tcp), "");
  for (const char* fine : {"tcp://node-3.cluster_a:1", "tcp://[::1]:65535", "tcp://n42:40000"}) {
    h.endpoint = fine;
    EXPECT_EQ(advertiseRefusal(h, tcp), "") << fine;
  }
  for (const char* bad : {"x", "tcp://node 3:40123", "tcp://node3", "tcp://node3:0", "tcp://node3:70000", "tcp://:40123",
                          "tcp://a/b:1", "tcp://[::g]:1", "ipc:///tmp/farm/renderer-1"}) {
    h.endpoint = bad;
    const std::string why = advertiseRefusal(h, tcp);
    EXPECT_NE(why.find("the renderer (pid 77) advertises an address its peers cannot connect to"), std::string::npos)
        << bad << ": " << why;
    EXPECT_NE(why.find("TESSERA_ADVERTISE_HOST"), std::string::npos) << why;
  }
  h.endpoint = "tcp://10.0.0.5:40123";
  EXPECT_NE(advertiseRefusal(h, ipc).find("is not a ipc:// endpoint"), std::string::npos) << advertiseRefusal(h, ipc);
  EXPECT_EQ(helloRefusal(h, "run", "", ipc), advertiseRefusal(h, ipc)) << "the master's one check of a Hello says it";
  h.endpoint = "ipc:///tmp/farm/renderer-1";
  EXPECT_EQ(advertiseRefusal(h, ipc), "");
  // A compositor says its host; on an ipc farm its host is not used.
  h.role = Role::Compositor;
  for (const char* fine : {"", "compositor-1", "10.1.2.3"}) {
    h.endpoint = fine;
    EXPECT_EQ(advertiseRefusal(h, tcp), "") << fine;
  }
  h.endpoint = "my host";
  EXPECT_NE(advertiseRefusal(h, tcp).find("the compositor (pid 77) advertises"), std::string::npos);
  EXPECT_NE(advertiseRefusal(h, tcp).find("'my host' has the character ' '"), std::string::npos) << advertiseRefusal(h, tcp);
  EXPECT_EQ(advertiseRefusal(h, ipc), "");
  h.role = Role::Display;  // advertises nothing its peers use
  EXPECT_EQ(advertiseRefusal(h, tcp), "");
}

}  // namespace
}  // namespace tessera::master
