// The output folder's lock (see output_lock.h). flock(2): the kernel drops it when the process
// dies however it dies, so a farm that crashed never blocks the next one.
#include "master/launcher/output_lock.h"

#include <regex>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "master/launcher/launcher.h"

namespace tessera::launcher {

OutputLock::OutputLock(const std::filesystem::path& folder) : path_(folder / ".tessera-farm") {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  // O_CLOEXEC: the farm's processes must not inherit the lock and keep it past tessera-up.
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw LaunchError("output folder " + folder.string() + ": cannot create " + path_.string() + ": " +
                      std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    char pid[32] = {0};
    const ssize_t got = ::pread(fd_, pid, sizeof pid - 1, 0);
    ::close(fd_);
    fd_ = -1;
    const std::string owner = got > 0 ? std::string(pid, (size_t)got) : "";
    throw LaunchError("output folder " + folder.string() + " is in use by another farm" +
                      (owner.empty() ? "" : " (tessera-up pid " + owner.substr(0, owner.find('\n')) + ")") +
                      ": wait for it to finish, or give this farm its own folder with TESSERA_OUT");
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != (ssize_t)me.size()) {
    // The pid is only for the other farm's message; the lock itself holds.
  }
}

OutputLock::~OutputLock() {
  if (fd_ < 0) return;
  std::error_code ec;
  std::filesystem::remove(path_, ec);
  ::close(fd_);
}

int removeOldFrames(const std::filesystem::path& folder) {
  static const std::regex frame(R"(frame_\d{6}\.(png|pam))");
  int removed = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(folder, ec))
    if (e.is_regular_file(ec) && std::regex_match(e.path().filename().string(), frame) &&
        std::filesystem::remove(e.path(), ec))
      ++removed;
  return removed;
}

}  // namespace tessera::launcher
