// The web view's server (libwebsockets: HTTP and WebSocket, one service thread): serves the
// page and its script, which are compiled into the program, and one WebSocket per viewer
// (/ws?token=...). Per viewer, at most 2 frames are unacknowledged and a newer frame replaces
// one not yet sent, so a slow or stalled viewer holds at most two frames (shared with the
// other viewers) and never slows the farm or the other viewers: writes never block (a frame
// goes out in 64 KiB pieces; a viewer that takes no piece for 5 s is closed, one that is silent
// for 10 s too). A viewer message is received 4 KiB at a time, so one over the 4 KiB
// limit is refused after its first 4 KiB. libwebsockets was chosen over civetweb for that by
// tessera-web-server-bench: civetweb reads a whole message (up to 2 GiB) before it can be
// refused, and on the web view's traffic both cost well under 0.1 ms of CPU a frame.
// Every refused connection and bad message is counted and logged once per kind.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "display/web_frame.h"

struct lws;
struct lws_context;

namespace tessera::display {

// TESSERA_WEB_TOKEN, or 128 random bits in hex (a new token per start).
std::string webToken();

struct WebAddress {
  std::string host;  // an address of this host
  int port = 0;      // 0: any free port
};
// HOST:PORT, :PORT or PORT (loopback); throws std::runtime_error naming `given` and the reason
// if the port is not a number or cannot be listened on.
WebAddress parseWebAddress(const std::string& given);

struct WebCounters {
  uint64_t viewers = 0;          // connected now
  uint64_t connections = 0;      // accepted since the start
  uint64_t refused = 0;          // WebSocket connections without the token, or over the limit
  uint64_t bad_messages = 0;     // malformed, oversized, binary or unknown viewer messages
  uint64_t bad_requests = 0;     // HTTP errors: unknown paths, garbage on the port
  uint64_t frames_sent = 0;
  uint64_t frames_replaced = 0;  // replaced by a newer one before a viewer could take it
  uint64_t cut_short = 0;        // viewers closed in the middle of a frame (stopped reading, or left)
  // For the latest (at most 1000) lossless and moving frames viewers acknowledged: ms from the
  // display presenting the frame to the acknowledgement (sent once the page has drawn it).
  std::vector<double> lossless_ms, moving_ms;
};

struct WebInput {
  nlohmann::json msg;  // {"t": "drag", ...}, checked
  std::chrono::steady_clock::time_point at;  // when it arrived
  uint32_t page = 0;  // the page's number for its load (page=... when it connected; 0: none)
  uint64_t n = 0;     // the page's number for this input (0: none)
};

class WebServer {
 public:
  static constexpr int kMaxViewers = 16;
  static constexpr int kMaxUnacked = 2;
  static constexpr size_t kMaxMessage = 4096;  // bytes of one viewer message

  // Listens on `address` (HOST:PORT; port 0 = any free port); throws std::runtime_error naming
  // the address when it cannot. `token`: what every WebSocket must present.
  WebServer(const std::string& address, std::string token);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  std::string url() const;  // http://HOST:PORT/#TOKEN: what to open
  int port() const { return port_; }
  // The newest frame for every viewer (and for viewers that connect later).
  void publish(std::shared_ptr<const WebFrame> frame);
  // The viewers' input messages since the last call, oldest first.
  std::vector<WebInput> takeInput();
  // Called (on the server's thread, with its lock held) when a viewer connects; the sink
  // re-sends its newest frame.
  void onViewer(std::function<void()> f);
  size_t viewers() const;
  WebCounters counters() const;

  struct Viewer;  // internal

 private:
  friend struct WebCallbacks;  // libwebsockets' callbacks (web_server.cpp)
  void badMessage(const std::string& why);

  std::string host_, token_;
  int port_ = 0;
  lws_context* ctx_ = nullptr;
  std::atomic<bool> stop_{false};
  std::thread service_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Viewer>> viewers_;
  std::shared_ptr<const WebFrame> latest_;
  std::vector<WebInput> input_;
  std::function<void()> on_viewer_;
  WebCounters counters_;
  uint64_t sent_ = 0, cut_short_ = 0;
  std::deque<double> lossless_ms_, moving_ms_;
  std::vector<std::string> logged_;  // kinds of bad input already logged
  std::unordered_set<lws*> unrequested_;  // connections that have not sent a request yet
};

}  // namespace tessera::display
