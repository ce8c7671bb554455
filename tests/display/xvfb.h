// Test helpers: a private Xvfb server on a display number it picks itself, and an XWD screenshot
// reader (xwd's file format: big-endian header, optional colormap, then ZPixmap rows).
#pragma once
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "common/image.h"

extern char** environ;

namespace tessera::display::testing {

inline bool onPath(const std::string& exe) {
  const char* path = std::getenv("PATH");
  std::string p = path ? path : "/usr/bin:/bin";
  for (size_t start = 0; start <= p.size();) {
    size_t end = p.find(':', start);
    if (end == std::string::npos) end = p.size();
    const std::string dir = p.substr(start, end - start);
    if (!dir.empty() && access((dir + "/" + exe).c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

// Starts `Xvfb -displayfd F -screen 0 1280x1024x24 -nolisten tcp`: the server picks a free
// display number itself and writes it to F once it accepts connections, so there is neither a
// race for a number nor a window opened before the server is ready (SDL would then fall back
// to an offscreen driver). stop() (or the destructor) ends it with SIGTERM, a bounded wait,
// then SIGKILL.
class Xvfb {
 public:
  bool start(std::string& error) {
    int fds[2];
    if (pipe(fds) != 0) { error = "pipe failed"; return false; }
    const std::string fd = std::to_string(fds[1]);
    std::vector<std::string> args = {"Xvfb", "-displayfd", fd, "-screen", "0", "1280x1024x24",
                                     "-nolisten", "tcp"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    const int rc = posix_spawnp(&pid_, "Xvfb", &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    close(fds[1]);
    if (rc != 0) { close(fds[0]); pid_ = -1; error = "cannot start Xvfb"; return false; }
    std::string line;
    for (int i = 0; i < 300 && line.find('\n') == std::string::npos; ++i) {  // up to 30 s
      pollfd p{fds[0], POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buf[32];
      const ssize_t got = read(fds[0], buf, sizeof buf);
      if (got <= 0) break;  // Xvfb exited
      line.append(buf, (size_t)got);
    }
    close(fds[0]);
    if (line.find('\n') == std::string::npos) {
      stop();
      error = "Xvfb did not report a display within 30 s";
      return false;
    }
    number_ = std::atoi(line.c_str());
    return true;
  }
  std::string display() const { return displayName(number_); }
  void stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    for (int i = 0; i < 100; ++i) {  // up to 2 s
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) { pid_ = -1; return; }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  ~Xvfb() { stop(); }

 private:
  // snprintf, not ":" + to_string: GCC 12 at -O3 warns falsely (-Wrestrict) on that concatenation.
  static std::string displayName(int n) {
    char name[16];
    std::snprintf(name, sizeof name, ":%d", n);
    return name;
  }
  pid_t pid_ = -1;
  int number_ = -1;
};

// Runs `xwd -root -silent -display D` and decodes its output into an opaque Image8.
// Handles the TrueColor ZPixmap layout Xvfb produces at depth 24 (any byte order).
inline Image8 screenshotRoot(const std::string& display, std::string& error) {
  const std::string cmd = "xwd -root -silent -display " + display;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) { error = "popen(xwd) failed"; return {}; }
  std::vector<uint8_t> b;
  uint8_t buf[65536];
  for (size_t got; (got = fread(buf, 1, sizeof buf, p)) > 0;) b.insert(b.end(), buf, buf + got);
  const int rc = pclose(p);
  auto u32 = [&](size_t field) {
    const uint8_t* q = &b[4 * field];
    return (uint32_t)q[0] << 24 | (uint32_t)q[1] << 16 | (uint32_t)q[2] << 8 | q[3];
  };
  if (rc != 0 || b.size() < 100) { error = "xwd failed (status " + std::to_string(rc) + ")"; return {}; }
  const uint32_t header_size = u32(0), version = u32(1), format = u32(2), width = u32(4),
                 height = u32(5), byte_order = u32(7), bpp = u32(11), bytes_per_line = u32(12),
                 rmask = u32(14), gmask = u32(15), bmask = u32(16), ncolors = u32(19);
  if (version != 7 || format != 2 || (bpp != 32 && bpp != 24)) {
    error = "unsupported XWD: version " + std::to_string(version) + " format " +
            std::to_string(format) + " bpp " + std::to_string(bpp);
    return {};
  }
  const size_t data = header_size + 12 * (size_t)ncolors;  // XWDColor entries are 12 bytes
  if (b.size() < data + (size_t)bytes_per_line * height) { error = "truncated XWD"; return {}; }
  auto channel = [](uint32_t v, uint32_t mask) {
    int shift = 0;
    while (mask && !(mask & 1)) { mask >>= 1; ++shift; }
    return (uint8_t)(((v >> shift) & mask) * 255 / (mask ? mask : 1));
  };
  Image8 img((int)width, (int)height);
  const int bytes = (int)bpp / 8;
  for (uint32_t y = 0; y < height; ++y) {
    const uint8_t* row = &b[data + (size_t)y * bytes_per_line];
    for (uint32_t x = 0; x < width; ++x) {
      const uint8_t* q = row + (size_t)x * bytes;
      uint32_t v = 0;
      for (int k = 0; k < bytes; ++k)  // byte_order 0 = LSBFirst
        v |= (uint32_t)q[k] << (8 * (byte_order == 0 ? k : bytes - 1 - k));
      uint8_t* d = img.at((int)x, (int)y);
      d[0] = channel(v, rmask), d[1] = channel(v, gmask), d[2] = channel(v, bmask), d[3] = 255;
    }
  }
  return img;
}

}  // namespace tessera::display::testing
