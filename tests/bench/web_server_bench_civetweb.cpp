// tessera-web-server-bench's civetweb server: the web view's options (display/web_server.cpp)
// and its way of sending: a thread per viewer writes a frame whenever fewer than 2 are
// unacknowledged. civetweb hands the data handler whole messages, so an oversized one is
// refused only after civetweb has read all of it.
#include <condition_variable>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "tests/bench/web_server_bench.h"

namespace tessera::bench {
namespace {

class CivetwebServer final : public BenchServer {
 public:
  CivetwebServer(int port, const Job& job) : BenchServer(job), frame_(job.frame_bytes, 7) {
    mg_init_library(0);
    const std::string address = "127.0.0.1:" + std::to_string(port);
    const char* options[] = {"listening_ports", address.c_str(), "num_threads", "8", "tcp_nodelay", "1",
                             "request_timeout_ms", "5000", "enable_keep_alive", "no", "websocket_timeout_ms", "3000",
                             "enable_websocket_ping_pong", "yes", nullptr};
    mg_callbacks callbacks{};
    ctx_ = mg_start(&callbacks, this, options);
    if (!ctx_) throw std::runtime_error("civetweb: cannot listen on " + address);
    mg_set_websocket_handler(ctx_, "/ws", nullptr, &CivetwebServer::onReady, &CivetwebServer::onData,
                             &CivetwebServer::onClose, this);
  }
  ~CivetwebServer() override {
    mg_stop(ctx_);
    if (sender_.joinable()) sender_.join();
  }

 private:
  static CivetwebServer& self(const mg_connection* c) {
    return *static_cast<CivetwebServer*>(mg_get_user_data(mg_get_context(c)));
  }
  static void onReady(mg_connection* c, void*) {
    CivetwebServer& s = self(c);
    s.connected();
    s.sender_ = std::thread([&s, c] { s.sendLoop(c); });
  }
  static int onData(mg_connection* c, int bits, char* data, size_t size, void*) {
    CivetwebServer& s = self(c);
    const int opcode = bits & 0x0f;
    if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
    if (size > kMaxMessage) return s.refuse(), 0;
    if (opcode == MG_WEBSOCKET_OPCODE_TEXT) s.acked(std::string(data, size));
    s.cv_.notify_one();
    return 1;
  }
  static void onClose(const mg_connection* c, void*) {
    CivetwebServer& s = self(c);
    {
      std::lock_guard lock(s.m_);
      s.closed_ = true;
    }
    s.cv_.notify_one();
  }
  void sendLoop(mg_connection* c) {
    while (true) {
      std::optional<uint64_t> id;
      {
        std::unique_lock lock(m_);
        cv_.wait_for(lock, std::chrono::milliseconds(50), [&] { return closed_ || (id = nextToSend()).has_value(); });
        if (closed_) return;
      }
      if (!id) continue;
      std::memcpy(frame_.data(), &*id, sizeof *id);
      if (mg_websocket_write(c, MG_WEBSOCKET_OPCODE_BINARY, frame_.data(), frame_.size()) < (int)frame_.size()) return;
    }
  }

  mg_context* ctx_ = nullptr;
  std::vector<char> frame_;
  std::mutex m_;
  std::condition_variable cv_;
  bool closed_ = false;
  std::thread sender_;
};

}  // namespace

std::unique_ptr<BenchServer> makeCivetwebServer(int port, const Job& job) {
  return std::make_unique<CivetwebServer>(port, job);
}

}  // namespace tessera::bench
