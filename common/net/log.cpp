#include "common/net/log.h"

#include <cstdlib>

#include <spdlog/sinks/stdout_color_sinks.h>

namespace tessera {

std::shared_ptr<spdlog::logger> setupLogging(const std::string& name) {
  auto logger = spdlog::get(name);
  if (!logger) logger = spdlog::stderr_color_mt(name);
  logger->set_pattern("%H:%M:%S.%e [%n] %l %v");
  const char* level = std::getenv("TESSERA_LOG");
  logger->set_level(level ? spdlog::level::from_str(level) : spdlog::level::info);
  spdlog::set_default_logger(logger);
  return logger;
}

DropCounter::~DropCounter() { summarise(); }

void DropCounter::drop(uint32_t sender, const std::string& reason) {
  ++total_;
  auto now = std::chrono::steady_clock::now();
  if (now - interval_start_ >= kInterval) {
    summarise();
    interval_start_ = now;
    lines_ = 0;
  }
  auto it = logged_.find(sender);
  if (it == logged_.end() && logged_.size() < kSendersTracked) it = logged_.emplace(sender, 0).first;
  const bool sender_quiet = it != logged_.end() && it->second >= kLoggedPerSender;
  if (!sender_quiet && lines_ < kLinesPerInterval) {
    ++lines_;
    const bool last = it != logged_.end() && ++it->second == kLoggedPerSender;
    spdlog::warn("dropped message sender={} reason=\"{}\" dropped_total={}{}",
                 sender == ~0u ? std::string("?") : std::to_string(sender), reason, total_,
                 last ? " (further drops from this sender are counted, summarised only)" : "");
    return;
  }
  ++unlogged_;
  if (unlogged_reasons_.count(reason) || unlogged_reasons_.size() < kReasonsSummarised) ++unlogged_reasons_[reason];
  else ++unlogged_reasons_["(other reasons)"];
}

void DropCounter::summarise() {
  if (!unlogged_) return;
  std::string reasons;
  for (const auto& [reason, n] : unlogged_reasons_) reasons += (reasons.empty() ? "\"" : ", \"") + reason + "\" x" + std::to_string(n);
  spdlog::warn("{} further drops not logged: reasons {} dropped_total={}", unlogged_, reasons, total_);
  unlogged_ = 0;
  unlogged_reasons_.clear();
}

}  // namespace tessera
