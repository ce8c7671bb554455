// The user's TESSERA_* settings: errors name the variable and the value typed, paths are the
// user's, unknown names get the closest known one.
#include "master/launcher/settings.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <cctype>
#include <iterator>
#include <map>
#include <set>

#include "master/launcher/launcher.h"

namespace tessera::launcher {
namespace {

namespace fs = std::filesystem;

CheckedSettings check(const std::map<std::string, std::string>& vars, const fs::path& dir = fs::temp_directory_path()) {
  std::vector<std::string> names;
  for (const auto& [k, v] : vars) names.push_back(k);
  return checkSettings(names, [&](const std::string& k) -> std::optional<std::string> {
    auto it = vars.find(k);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  }, dir);
}

std::string errorOf(const std::map<std::string, std::string>& vars) {
  try {
    check(vars);
  } catch (const LaunchError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Settings, ErrorsNameTheVariableAndTheValueTyped) {
  EXPECT_EQ(errorOf({{"TESSERA_RENDERERS", "0"}}), "TESSERA_RENDERERS=0: expected a whole number from 1 to 1024 (renderer processes)");
  EXPECT_EQ(errorOf({{"TESSERA_FRAMES", "-5"}}), "TESSERA_FRAMES=-5: expected a whole number from -1 to 100000000 (frames to render; -1: the scene's orbit, 0: interactive until the window closes or Ctrl-C)");
  EXPECT_EQ(errorOf({{"TESSERA_IN_FLIGHT", "3x"}}), "TESSERA_IN_FLIGHT=3x: expected a whole number from 1 to 64");
  EXPECT_EQ(errorOf({{"TESSERA_CODEC", "gzip"}}), "TESSERA_CODEC=gzip: expected one of none,lzo,lz4,zstd");
  EXPECT_EQ(errorOf({{"TESSERA_FRAMES", "-1"}, {"TESSERA_CODEC", "lz4"}, {"TESSERA_RENDERERS", ""}}), "no error");
}

TEST(Settings, EveryVariableTheComposeFileReadsIsASetting) {
  // A variable compose.yaml reads but the list lacks was warned about as "not a Tessera
  // setting (ignored)" while the farm used it, and its value went unchecked (TESSERA_CACHE_MB).
  std::ifstream in(TESSERA_SOURCE_DIR "/compose.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::set<std::string> names;
  for (size_t at = text.find("${TESSERA_"); at != std::string::npos; at = text.find("${TESSERA_", at + 2)) {
    size_t end = at + 2;
    while (end < text.size() && (std::isupper((unsigned char)text[end]) || text[end] == '_')) ++end;
    names.insert(text.substr(at + 2, end - at - 2));
  }
  ASSERT_GT(names.size(), 20u);
  for (const auto& name : names) EXPECT_TRUE(check({{name, ""}}).warnings.empty()) << name;
  EXPECT_EQ(errorOf({{"TESSERA_CACHE_MB", "-1"}}),
            "TESSERA_CACHE_MB=-1: expected a whole number from 0 to 1048576 (MiB of a time series' steps a renderer "
            "holds besides the one shown)");
}

TEST(Settings, UnknownNamesGetTheClosestKnownOne) {
  const auto c = check({{"TESSERA_RENDERER", "4"}, {"TESSERA_SOMETHING_ELSE", "1"}, {"HOME", "/root"}});
  ASSERT_EQ(c.warnings.size(), 2u);
  EXPECT_EQ(c.warnings[0], "TESSERA_RENDERER is not a Tessera setting (ignored); did you mean TESSERA_RENDERERS?");
  EXPECT_EQ(c.warnings[1], "TESSERA_SOMETHING_ELSE is not a Tessera setting (ignored)");
}

TEST(Settings, RelativePathsAreTheUsersFolder) {
  const fs::path dir = fs::temp_directory_path() / ("tessera-settings-" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "blobs.yaml") << "volume: {generator: {name: hollow-shell}}\n";
  const auto c = check({{"TESSERA_SCENE", "blobs.yaml"}, {"TESSERA_OUT", "frel"}, {"TESSERA_KEYS", "/abs/keys"}}, dir);
  EXPECT_EQ(c.overrides.at("TESSERA_SCENE"), (dir / "blobs.yaml").string());
  EXPECT_EQ(c.overrides.at("TESSERA_OUT"), (dir / "frel").string());
  EXPECT_EQ(c.overrides.count("TESSERA_KEYS"), 0u) << "absolute paths stay as typed";
  try {
    check({{"TESSERA_SCENE", "missing.yaml"}}, dir);
    ADD_FAILURE() << "no error";
  } catch (const LaunchError& e) {
    EXPECT_EQ(std::string(e.what()), "TESSERA_SCENE=missing.yaml: no such file or folder (looked for " + (dir / "missing.yaml").string() + ")");
  }
  fs::remove_all(dir);
}

// The real launcher refuses before starting anything, naming the variable.
TEST(Settings, TesseraUpRefusesABadSettingByName) {
  const std::string binary = TESSERA_BINARY_DIR "/bin/tessera-up";
  if (access(binary.c_str(), X_OK) != 0) GTEST_SKIP() << binary << " not built";
  FILE* p = popen(("env TESSERA_RENDERERS=0 " + binary + " --dry-run " TESSERA_SOURCE_DIR "/compose.yaml 2>&1").c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (fgets(buf, sizeof buf, p)) out += buf;
  EXPECT_NE(pclose(p), 0);
  EXPECT_NE(out.find("TESSERA_RENDERERS=0: expected a whole number from 1 to 1024"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::launcher
