// The launcher tests' fixture: a temporary folder (DIR in compose files), running a
// compose text through the library with its output lines captured.
#pragma once
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "master/launcher/launcher.h"

namespace tessera::launcher {

class LauncherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/tessera-launcher-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  ComposeProject project(const std::string& yaml) {
    ComposeOptions options;
    options.overrides["DIR"] = dir_.string();
    return parseCompose(yaml, dir_, options, "compose.yaml");
  }

  // Runs the farm through the library; returns the exit code and fills lines_.
  int run(const std::string& yaml, std::chrono::milliseconds stop_timeout = std::chrono::milliseconds(5000)) {
    LaunchOptions options;
    options.handle_signals = false;
    options.stop_timeout = stop_timeout;
    options.restart = restart_limits_;
    options.output = [this](std::string_view line) { lines_.emplace_back(line); };
    return launch(project(yaml), options);
  }

  bool hasLine(const std::string& line) const {
    return std::find(lines_.begin(), lines_.end(), line) != lines_.end();
  }
  std::string allLines() const {
    std::string s;
    for (const auto& l : lines_) s += l + "\n";
    return s;
  }

  // Pids the children wrote into DIR/*.pid.
  std::vector<pid_t> recordedPids() const {
    std::vector<pid_t> pids;
    for (const auto& e : std::filesystem::directory_iterator(dir_)) {
      if (e.path().extension() != ".pid") continue;
      pid_t pid = 0;
      std::ifstream(e.path()) >> pid;
      if (pid > 0) pids.push_back(pid);
    }
    return pids;
  }
  static bool alive(pid_t pid) { return kill(pid, 0) == 0; }

  bool hasLineStarting(const std::string& prefix) const {
    return std::any_of(lines_.begin(), lines_.end(), [&](const std::string& l) { return l.rfind(prefix, 0) == 0; });
  }
  size_t indexOf(const std::string& line) const {
    return std::find(lines_.begin(), lines_.end(), line) - lines_.begin();
  }

  // Lines of DIR/<name> (children append one per event, e.g. per start).
  std::vector<std::string> fileLines(const std::string& name) const {
    std::vector<std::string> out;
    std::ifstream in(dir_ / name);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }

  std::filesystem::path dir_;
  std::vector<std::string> lines_;
  RestartLimits restart_limits_;  // what run() passes to the launcher
};

}  // namespace tessera::launcher
