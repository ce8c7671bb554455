// The farm across emulated hosts (tests/cluster/emulated_cluster.sh): every process in its
// own network namespace behind a 100 Mbit/s link, the farm over TCP with CURVE between the
// hosts' addresses. Its orbit must equal the one-process render (the sort-last contract),
// every host's link must have carried the farm's traffic, and no namespace may remain.
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

std::string namespaces() { return runCommand("ip netns list", 10).output; }

// swap: binary swap between the renderers (the default across hosts), over their own links
// (each renderer binds and advertises its swap socket on its host, as compositors do).
void expectOrbitAcrossHosts(int renderers, bool swap) {
  if (geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
  if (runCommand("ip netns list && tc -V", 10).exit_code != 0) GTEST_SKIP() << "iproute2 (ip, tc) is not installed";
  FarmDir dir(swap ? "cluster-swap" : "cluster");
  const int frames = 3;
  const auto scene = dir.writeScene(frames);
  const std::string out = (dir.path() / "out").string();
  const auto r = runCommand("env TESSERA_PREMULTIPLIED=1 TESSERA_SCENE=" + scene.string() + " TESSERA_RENDERERS=" +
                                std::to_string(renderers) + " TESSERA_COMPOSITORS=1 TESSERA_FRAMES=" +
                                std::to_string(frames) + (swap ? " TESSERA_COMPOSITING=auto" : " TESSERA_COMPOSITING=direct-send") +
                                " " TESSERA_SOURCE_DIR "/tests/cluster/emulated_cluster.sh --rate 100mbit --out " + out +
                                " --bin " TESSERA_BINARY_DIR "/bin",
                            240);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("endpoints tcp://10.77.0.1:5550"), std::string::npos) << r.output;
  if (swap) {
    EXPECT_NE(r.output.find("binary swap among " + std::to_string(renderers) + " renderers"), std::string::npos) << r.output;
  }
  for (int k = 0; k < frames; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;

  std::map<std::string, std::pair<long, long>> links;  // host -> bytes sent, received
  std::ifstream in(dir.path() / "out" / "links.tsv");
  std::string host;
  long sent = 0, received = 0, packets_sent = 0, packets_received = 0;
  while (in >> host >> sent >> received >> packets_sent >> packets_received) {
    links[host] = {sent, received};
    EXPECT_GT(packets_sent, 0) << host;
    EXPECT_LE(packets_sent, sent / 40) << host << ": a packet carries at least its 40 bytes of headers";
  }
  ASSERT_EQ(links.size(), 3u + renderers) << "master, display, the renderers, 1 compositor";
  // Each renderer sends its pieces of 3 frames (97x83 rgba, compressed, some kB at least);
  // the display receives the composited frames. With binary swap the renderers also receive
  // their partners' bands and send their own finished bands to the display; the compositor
  // has no part in the frames. 3 renderers swap thirds in one round: every one receives.
  int receiving = 0;
  for (int i = 1; i <= renderers; ++i) {
    const std::string h = "renderer-" + std::to_string(i);
    EXPECT_GT(links[h].first, 4000) << h;
    receiving += links[h].second > 2000;
  }
  if (swap) {
    EXPECT_EQ(receiving, renderers) << "renderers that received swap pieces";
  }
  if (!swap) {
    EXPECT_GT(links["compositor-1"].first, 4000);
  }
  EXPECT_GT(links["display"].second, 4000);
  EXPECT_EQ(namespaces().find("tcl"), std::string::npos) << "left behind:\n" << namespaces();
}

TEST(EmulatedCluster, OrbitAcrossHostsMatchesOneProcessRender) { expectOrbitAcrossHosts(2, false); }
// Three renderers: binary swap as one round of three (proto::swapRadices) across hosts.
TEST(EmulatedCluster, BinarySwapAcrossHostsMatchesOneProcessRender) { expectOrbitAcrossHosts(3, true); }

// A link fails during an orbit of 200 frames by 2 renderers while both ends still reach the
// master (tests/cluster/emulated_cluster.sh --cut): what `from` sends `to` vanishes. Frames
// stall until the master's deadline, the sender is dropped and its work split anew, and the
// farm goes on: every frame is written and equals the one-process render. `blame`: what the
// master's deadline message must say.
void expectFarmOutlivesACut(const std::string& compositing, int compositors, const std::string& from,
                            const std::string& to, const std::string& blame) {
  if (geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
  if (runCommand("ip netns list && tc -V", 10).exit_code != 0) GTEST_SKIP() << "iproute2 (ip, tc) is not installed";
  FarmDir dir("cluster-cut");
  const int frames = 200, cut_after = 10;  // the cut lands a few frames later: the script polls
  const auto scene = dir.writeScene(frames);
  const auto r = runCommand("env TESSERA_PREMULTIPLIED=1 TESSERA_SCENE=" + scene.string() +
                                " TESSERA_RENDERERS=2 TESSERA_COMPOSITORS=" + std::to_string(compositors) +
                                " TESSERA_COMPOSITING=" + compositing + " TESSERA_FRAMES=" +
                                std::to_string(frames) + " " TESSERA_SOURCE_DIR "/tests/cluster/emulated_cluster.sh --out " +
                                (dir.path() / "out").string() + " --cut " + from + "," + to + "," + std::to_string(cut_after) +
                                " --bin " TESSERA_BINARY_DIR "/bin",
                            240);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_NE(r.output.find(from + "'s link to " + to + " is cut"), std::string::npos) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(frame=(\d+) missed its deadline[^\n]*)")))
      << "the cut stalled no frame:\n" << r.output;
  EXPECT_NE(m.str().find(blame), std::string::npos) << m.str();
  const int stalled = std::stoi(m[1]);
  EXPECT_GE(stalled, cut_after);
  ASSERT_LT(stalled, frames - 3) << "the farm was done before the cut mattered";
  for (int k : {0, stalled - 1, stalled, stalled + 1, stalled + 2, stalled + 3, frames - 1})
    EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;
  for (int k = 0; k < frames; ++k) EXPECT_TRUE(fs::exists(dir.frame(k))) << "frame " << k << " was not written";
  EXPECT_EQ(namespaces().find("tcl"), std::string::npos) << "left behind:\n" << namespaces();
}

// Between swap partners: one awaits the other's piece (whichever the master drops, the other
// renders the whole volume).
TEST(EmulatedCluster, ALinkCutBetweenSwapPartnersStallsFramesButLosesNone) {
  expectFarmOutlivesACut("binary-swap", 1, "renderer-2", "renderer-1", "): renderer ");
}

// A renderer's link to the display: the display, whose loss would end the farm, says in its
// heartbeats whose band it awaits, and the master drops that renderer instead.
TEST(EmulatedCluster, ALinkCutBetweenARendererAndTheDisplayCostsTheRendererNotTheFarm) {
  expectFarmOutlivesACut("binary-swap", 1, "renderer-2", "display", "display 0 awaits renderer");
}

// Direct send: a compositor says whose piece it lacks, and the master drops that renderer
// (before, the compositor, whose loss did not mend the link).
TEST(EmulatedCluster, ALinkCutBetweenARendererAndACompositorCostsTheRenderer) {
  expectFarmOutlivesACut("direct-send", 2, "renderer-2", "compositor-1", "awaits renderer");
}

}  // namespace
}  // namespace tessera::test
