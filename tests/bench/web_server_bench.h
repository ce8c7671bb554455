// tessera-web-server-bench's servers: what both libraries' servers share (the web view's flow
// control: at most 2 frames unacknowledged, acknowledgements by id, messages over 4 KiB refused).
#pragma once
#include <civetweb.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace tessera::bench {

constexpr size_t kMaxMessage = 4096;

struct Job {
  std::string name;
  size_t frame_bytes;  // of each frame pushed to the viewer
  int frames;          // how many (0: none)
  size_t send_bytes;   // the viewer sends one message of this size (0: none)
};

class BenchServer {
 public:
  explicit BenchServer(const Job& job) : job_(job) {}
  virtual ~BenchServer() = default;

  void connected() {
    std::lock_guard lock(m_);
    sent_ = 0;
  }
  // The id of the next frame to write now, if fewer than 2 are unacknowledged.
  std::optional<uint64_t> nextToSend() {
    std::lock_guard lock(m_);
    if (sent_ >= (uint64_t)job_.frames || written_.size() >= 2) return {};
    written_[sent_] = std::chrono::steady_clock::now();
    return sent_++;
  }
  void acked(const std::string& text) {
    std::lock_guard lock(m_);
    const auto it = written_.find(std::strtoull(text.c_str(), nullptr, 10));
    if (it == written_.end()) return;
    ack_ms_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - it->second).count());
    written_.erase(it);
  }
  void refuse() { refused_ = true; }
  bool refused() const { return refused_; }
  double acks() const {
    std::lock_guard lock(m_);
    return (double)ack_ms_.size();
  }
  double medianAckMs() const {
    std::lock_guard lock(m_);
    if (ack_ms_.empty()) return 0;
    std::vector<double> v = ack_ms_;
    std::nth_element(v.begin(), v.begin() + (long)(v.size() / 2), v.end());
    return v[v.size() / 2];
  }

 protected:
  const Job job_;

 private:
  mutable std::mutex m_;
  uint64_t sent_ = 0;
  std::map<uint64_t, std::chrono::steady_clock::time_point> written_;
  std::vector<double> ack_ms_;
  std::atomic<bool> refused_{false};
};

// The civetweb server, set up as the web view's (web_server_bench_civetweb.cpp).
std::unique_ptr<BenchServer> makeCivetwebServer(int port, const Job& job);

}  // namespace tessera::bench
