// Logging (spdlog, one named logger per process, level from TESSERA_LOG) and the counter
// of dropped peer messages: every drop is counted; the first few per sender are logged.
// DropCounter is used from one thread.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

namespace tessera {

// Creates the process logger `name` (stderr, "[name] level message") and makes it default.
std::shared_ptr<spdlog::logger> setupLogging(const std::string& name);

class DropCounter {
 public:
  // Counts one dropped message from `sender` (a rank, or ~0u if unknown) and logs why,
  // at most kLoggedPerSender times per sender so a flood cannot drown the log.
  void drop(uint32_t sender, const std::string& reason);
  uint64_t total() const { return total_; }
  static constexpr int kLoggedPerSender = 3;

 private:
  uint64_t total_ = 0;
  std::map<uint32_t, int> logged_;
};

}  // namespace tessera
