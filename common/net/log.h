// Logging (spdlog, one named logger per process, level from TESSERA_LOG) and the counter
// of dropped peer messages: every drop is counted; few are logged, so that no peer can
// flood the log, whatever sender it claims. DropCounter is used from one thread.
#pragma once
#include <chrono>
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
  DropCounter() = default;
  DropCounter(const DropCounter&) = delete;
  DropCounter& operator=(const DropCounter&) = delete;
  ~DropCounter();  // logs the summary of drops not logged yet

  // Counts one dropped message from `sender` (a rank, or ~0u if unknown: claimed, not
  // trusted) and logs why: at most kLoggedPerSender lines per sender and, whatever the
  // senders, at most kLinesPerInterval lines per kInterval. The drops not logged are
  // summarised in one line ("N further drops not logged: reasons ...") at the next drop
  // after the interval, or when the counter goes away.
  void drop(uint32_t sender, const std::string& reason);
  uint64_t total() const { return total_; }

  static constexpr int kLoggedPerSender = 3;
  static constexpr int kLinesPerInterval = 20;
  static constexpr std::chrono::seconds kInterval{10};
  static constexpr size_t kSendersTracked = 256;   // claimed senders remembered (memory bound)
  static constexpr size_t kReasonsSummarised = 8;  // distinct reasons named in a summary

 private:
  void summarise();

  uint64_t total_ = 0;
  std::map<uint32_t, int> logged_;  // lines logged per claimed sender
  int lines_ = 0;                   // lines logged in this interval
  std::chrono::steady_clock::time_point interval_start_ = std::chrono::steady_clock::now();
  uint64_t unlogged_ = 0;
  std::map<std::string, uint64_t> unlogged_reasons_;
};

}  // namespace tessera
