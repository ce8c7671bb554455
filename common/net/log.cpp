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

void DropCounter::drop(uint32_t sender, const std::string& reason) {
  ++total_;
  int& n = logged_[sender];
  if (n < kLoggedPerSender) {
    spdlog::warn("dropped message sender={} reason=\"{}\" dropped_total={}{}",
                 sender == ~0u ? std::string("?") : std::to_string(sender), reason, total_,
                 ++n == kLoggedPerSender ? " (further drops from this sender are counted only)" : "");
  }
}

}  // namespace tessera
