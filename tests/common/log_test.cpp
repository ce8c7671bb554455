#include "common/net/log.h"

#include <gtest/gtest.h>

#include <sstream>

#include <spdlog/sinks/ostream_sink.h>

namespace tessera {
namespace {

// Captures the default logger's lines while alive.
class CapturedLog {
 public:
  CapturedLog() : previous_(spdlog::default_logger()) {
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(out_);
    sink->set_pattern("%l %v");
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("captured", sink));
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  std::vector<std::string> lines() const {
    std::vector<std::string> v;
    std::istringstream in(out_.str());
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  }

 private:
  std::ostringstream out_;
  std::shared_ptr<spdlog::logger> previous_;
};

// Defect: the rate limit keyed on the claimed sender, so varying it flooded the log.
TEST(DropCounter, DistinctClaimedSendersCannotFloodTheLog) {
  CapturedLog log;
  {
    DropCounter drops;
    for (uint32_t s = 0; s < 900; ++s) drops.drop(s, s % 2 ? "bad magic" : "checksum mismatch");
    EXPECT_EQ(drops.total(), 900u);
  }  // the summary of what was not logged comes out at the latest here
  auto lines = log.lines();
  EXPECT_LE(lines.size(), (size_t)DropCounter::kLinesPerInterval + 1);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("further drops not logged"), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("bad magic"), std::string::npos) << lines.back();
}

TEST(DropCounter, FewDropsAreAllLogged) {
  CapturedLog log;
  {
    DropCounter drops;
    drops.drop(1, "bad magic");
    drops.drop(2, "bad magic");
  }
  EXPECT_EQ(log.lines().size(), 2u);
}

}  // namespace
}  // namespace tessera
