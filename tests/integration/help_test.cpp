// Every program explains itself: --help exits 0 and describes the program; a wrong output
// extension is refused by name instead of writing PNG bytes into a .jpg.
#include <gtest/gtest.h>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(Help, EveryProgramAnswersHelpWithExitZero) {
  for (const char* program : {"tessera-up", "tessera-master", "tessera-renderer", "tessera-compositor",
                              "tessera-display", "tessera-render", "tessera-keys", "tessera-dump-volume"}) {
    const auto r = runCommand(bin(program) + " --help", 30);
    EXPECT_EQ(r.exit_code, 0) << program << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage:"), std::string::npos) << program << "\n" << r.output;
    EXPECT_NE(r.output.find("--help"), std::string::npos) << program;
  }
}

TEST(Help, TesseraRenderRefusesAnExtensionItDoesNotWrite) {
  FarmDir dir("ext");
  const auto r = runCommand(bin("tessera-render") + " -o " + (dir.path() / "x.jpg").string(), 60);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("x.jpg': tessera-render writes PNG only; name the file .png"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "x.jpg"));
}

}  // namespace
}  // namespace tessera::test
