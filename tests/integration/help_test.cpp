// Every program explains itself: --help exits 0 and describes the program; a wrong output
// extension is refused by name instead of writing PNG bytes into a .jpg.
#include <gtest/gtest.h>

#include "tests/integration/farm_util.h"

namespace tessera::test {
namespace {

TEST(Help, EveryProgramAnswersHelpWithExitZero) {
  for (const char* program : {"tessera-up", "tessera-master", "tessera-renderer", "tessera-compositor",
                              "tessera-display", "tessera-render", "tessera-info", "tessera-keys", "tessera-dump-volume"}) {
    const auto r = runCommand(bin(program) + " --help", 30);
    EXPECT_EQ(r.exit_code, 0) << program << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage:"), std::string::npos) << program << "\n" << r.output;
    EXPECT_NE(r.output.find("--help"), std::string::npos) << program;
  }
}

TEST(Help, EveryHelpShowsTheDefaults) {
  // The line of `option` in `program --help` must show `value` as its default.
  auto expectDefault = [](const char* program, const std::string& option, const std::string& value) {
    const auto r = runCommand(bin(program) + " --help", 30);
    const size_t at = r.output.find("  " + option + " ");
    ASSERT_NE(at, std::string::npos) << program << " has no " << option << "\n" << r.output;
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    // CLI11 2.3 (Debian 12) writes the default as "=value" at the end of the option's column.
    EXPECT_NE((line + " ").find("=" + value + " "), std::string::npos) << program << ": " << line;
  };
  expectDefault("tessera-master", "--in-flight", "3");
  expectDefault("tessera-master", "--codec", "lzo");
  expectDefault("tessera-renderer", "--threads", "0");
  expectDefault("tessera-display", "--out", "out");
  expectDefault("tessera-render", "--bricks", "1");
  expectDefault("tessera-info", "--bins", "16");
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
