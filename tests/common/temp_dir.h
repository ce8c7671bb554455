// A folder of its own for one test (named after the test and the process, so parallel
// ctest runs never share it), removed with everything in it when the test ends.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace tessera::test {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) {
    path = std::filesystem::temp_directory_path() / ("tessera_" + name + "_" + std::to_string(getpid()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path / name).string(); }
  // Writes `n` bytes to `name` in the folder and returns its path.
  std::string write(const std::string& name, const void* data, size_t n) const {
    std::ofstream(file(name), std::ios::binary).write(static_cast<const char*>(data), (std::streamsize)n);
    return file(name);
  }
};

}  // namespace tessera::test
