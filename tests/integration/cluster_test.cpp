// The farm across emulated hosts (tests/cluster/emulated_cluster.sh): every process in its
// own network namespace behind a 100 Mbit/s link, the farm over TCP with CURVE between the
// hosts' addresses. Its orbit must equal the one-process render (the sort-last contract),
// every host's link must have carried the farm's traffic, and no namespace may remain.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <sstream>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

std::string namespaces() { return runCommand("ip netns list", 10).output; }

TEST(EmulatedCluster, OrbitAcrossHostsMatchesOneProcessRender) {
  if (geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
  if (runCommand("ip netns list && tc -V", 10).exit_code != 0) GTEST_SKIP() << "iproute2 (ip, tc) is not installed";
  FarmDir dir("cluster");
  const int frames = 3;
  const auto scene = dir.writeScene(frames);
  const std::string out = (dir.path() / "out").string();
  const auto r = runCommand("env TESSERA_PREMULTIPLIED=1 TESSERA_SCENE=" + scene.string() +
                                " TESSERA_RENDERERS=2 TESSERA_COMPOSITORS=1 TESSERA_FRAMES=" + std::to_string(frames) +
                                " " TESSERA_SOURCE_DIR "/tests/cluster/emulated_cluster.sh --rate 100mbit --out " + out +
                                " --bin " TESSERA_BINARY_DIR "/bin",
                            240);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("endpoints tcp://10.77.0.1:5550"), std::string::npos) << r.output;
  for (int k = 0; k < frames; ++k) EXPECT_TRUE(dir.matches(dir.farmFrame(k), dir.reference(scene, k), 1, "frame_" + std::to_string(k))) << "frame " << k;

  std::map<std::string, std::pair<long, long>> links;  // host -> bytes sent, received
  std::ifstream in(dir.path() / "out" / "links.tsv");
  std::string host;
  long sent = 0, received = 0;
  while (in >> host >> sent >> received) links[host] = {sent, received};
  ASSERT_EQ(links.size(), 5u) << "master, display, 2 renderers, 1 compositor";
  // Each renderer sends its pieces of 3 frames (97x83 rgba, compressed, some kB at least);
  // the display receives the composited frames.
  for (const char* h : {"renderer-1", "renderer-2", "compositor-1"}) EXPECT_GT(links[h].first, 4000) << h;
  EXPECT_GT(links["display"].second, 4000);
  EXPECT_EQ(namespaces().find("tcl"), std::string::npos) << "left behind:\n" << namespaces();
}

}  // namespace
}  // namespace tessera::test
