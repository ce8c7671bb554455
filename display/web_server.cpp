// civetweb handlers of the web view. See web_server.h.
#include "display/web_server.h"

#include <civetweb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <condition_variable>
#include <deque>
#include <cstring>
#include <stdexcept>
#include <thread>

#include <spdlog/spdlog.h>

#include "display/web_assets.h"

namespace tessera::display {

struct WebServer::Viewer {
  mg_connection* conn = nullptr;
  std::mutex m;
  std::condition_variable cv;
  struct Sent {
    uint64_t id;
    bool lossless;
    std::chrono::steady_clock::time_point shown_at;
  };
  uint32_t page = 0;  // the page's number for its load (0: none given)
  std::chrono::steady_clock::time_point connected_at;
  std::shared_ptr<const WebFrame> pending;  // the newest frame not yet sent
  std::deque<Sent> unacked;                 // sent and not acknowledged yet
  bool closing = false;
  bool dead = false;  // a write failed or was cut short: the connection is closed on its next read
  std::thread sender;
};

namespace {

constexpr size_t kMaxQueuedInput = 1024;  // input messages between two display polls

bool sameToken(const std::string& a, const std::string& b) {
  unsigned diff = a.size() != b.size();
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) diff |= (unsigned)(a[i] ^ b[i]);
  return diff == 0;  // time independent of where they differ
}

std::string queryValue(const char* query, const std::string& key) {
  if (!query) return {};
  char value[256];
  const int n = mg_get_var(query, std::strlen(query), key.c_str(), value, sizeof value);
  return n >= 0 ? std::string(value, (size_t)n) : std::string();
}

// Why a viewer's input message is unusable ("" when it is fine): numbers finite and bounded.
std::string badInput(const nlohmann::json& msg, const std::string& type) {
  auto number = [&](const char* key, double limit) {
    return msg.contains(key) && msg[key].is_number() && std::abs(msg[key].get<double>()) <= limit;
  };
  if (type == "drag" && !(number("dx", 1e4) && number("dy", 1e4))) return "a drag without numbers dx, dy within 10000";
  if (type == "wheel" && !number("notches", 100)) return "a wheel without a number of notches within 100";
  if (type == "key" && !(msg.contains("key") && msg["key"].is_string())) return "a key without a key";
  if (msg.contains("n") && !msg["n"].is_number_unsigned()) return "an input number n that is not a whole number";
  return "";
}

WebServer* self(const mg_connection* conn) {
  return static_cast<WebServer*>(mg_get_user_data(mg_get_context(conn)));
}

// One viewer's sending thread: the newest frame, when fewer than kMaxUnacked are unacknowledged.
// mg_websocket_write takes the connection's lock itself. A write that fails or is cut short
// (a viewer that stopped reading past the write timeout) would leave half a frame in the
// stream: the viewer is dead, and civetweb's ping (no pong) or its next message closes it.
void sendLoop(WebServer::Viewer& v, std::atomic<uint64_t>& sent, std::atomic<uint64_t>& cut_short) {
  std::unique_lock lock(v.m);
  while (true) {
    v.cv.wait(lock, [&] { return v.closing || (v.pending && (int)v.unacked.size() < WebServer::kMaxUnacked); });
    if (v.closing) return;
    auto frame = std::move(v.pending);
    v.pending.reset();
    v.unacked.push_back({frame->id, frame->lossless, frame->shown_at});
    lock.unlock();
    const int n = mg_websocket_write(v.conn, MG_WEBSOCKET_OPCODE_BINARY, reinterpret_cast<const char*>(frame->message.data()),
                                     frame->message.size());
    lock.lock();
    if (n < 0 || (size_t)n < frame->message.size()) {
      cut_short.fetch_add(1);
      v.dead = true;
      return;
    }
    sent.fetch_add(1);
  }
}

}  // namespace

std::string webToken() {
  if (const char* t = std::getenv("TESSERA_WEB_TOKEN"); t && *t) return t;
  std::random_device rd;
  std::string token;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", (unsigned)rd());
    token += part;
  }
  return token;
}

WebServer::WebServer(const std::string& given, std::string token) : token_(std::move(token)) {
  if (token_.size() > 200) throw std::runtime_error("the web view's token is longer than 200 characters");
  // PORT or :PORT listens on loopback: nothing is served beyond this host unless asked.
  const size_t colon = given.rfind(':');
  host_ = colon == std::string::npos || colon == 0 ? "127.0.0.1" : given.substr(0, colon);
  const std::string address = host_ + ":" + (colon == std::string::npos ? given : given.substr(colon + 1));
  mg_init_library(0);
  mg_callbacks callbacks{};
  callbacks.http_error = &WebServer::onHttpError;
  // A WebSocket holds a worker thread while it is open: the viewers, plus some for pages.
  const std::string threads = std::to_string(kMaxViewers + 8);
  // Pings every 3 s: a viewer whose link died (a laptop asleep, a dropped NAT entry) is
  // closed instead of holding its slot until TCP gives up. A write that makes no progress for
  // 5 s (request_timeout_ms; any progress restarts it, so a slow link is fine) is cut short.
  // tcp_nodelay: a frame goes out as civetweb writes it (its header, then the payload);
  // with Nagle's algorithm the payload waited for the viewer's delayed ACK, ~20 ms a frame.
  const char* options[] = {"listening_ports", address.c_str(), "num_threads", threads.c_str(), "tcp_nodelay", "1",
                           "request_timeout_ms", "5000", "enable_keep_alive", "no",
                           "websocket_timeout_ms", "3000", "enable_websocket_ping_pong", "yes", nullptr};
  ctx_ = mg_start(&callbacks, this, options);
  if (!ctx_) throw std::runtime_error("--web " + address + ": cannot listen there (in use, or not this host's address?)");
  mg_server_port ports[4];
  if (mg_get_server_ports(ctx_, 4, ports) >= 1) port_ = ports[0].port;
  mg_set_request_handler(ctx_, "/", &WebServer::onRequest, this);
  mg_set_websocket_handler(ctx_, "/ws", &WebServer::onConnect, &WebServer::onReady, &WebServer::onData,
                           &WebServer::onClose, this);
}

WebServer::~WebServer() {
  // Closes every connection; each close handler ends its viewer's thread. A write blocked on
  // a stalled viewer sees the stop within civetweb's 2 s socket quantum.
  mg_stop(ctx_);
}

std::string WebServer::url() const { return "http://" + host_ + ":" + std::to_string(port_) + "/#" + token_; }

void WebServer::publish(std::shared_ptr<const WebFrame> frame) {
  std::lock_guard lock(mutex_);
  latest_ = frame;
  for (auto& v : viewers_) {
    std::lock_guard vl(v->m);
    if (v->pending) ++counters_.frames_replaced;
    v->pending = frame;
    v->cv.notify_one();
  }
}

void WebServer::onViewer(std::function<void()> f) {
  std::lock_guard lock(mutex_);
  on_viewer_ = std::move(f);
}

size_t WebServer::viewers() const {
  std::lock_guard lock(mutex_);
  return viewers_.size();
}

std::vector<WebInput> WebServer::takeInput() {
  std::lock_guard lock(mutex_);
  return std::exchange(input_, {});
}

WebCounters WebServer::counters() const {
  std::lock_guard lock(mutex_);
  WebCounters c = counters_;
  c.viewers = viewers_.size();
  c.frames_sent = sent_.load();
  c.cut_short = cut_short_.load();
  c.lossless_ms.assign(lossless_ms_.begin(), lossless_ms_.end());
  c.moving_ms.assign(moving_ms_.begin(), moving_ms_.end());
  return c;
}

void WebServer::badMessage(const std::string& why) {  // with mutex_ held
  ++counters_.bad_messages;
  if (std::find(logged_.begin(), logged_.end(), why) != logged_.end()) return;
  logged_.push_back(why);
  spdlog::warn("web view: refused a viewer message: {} (counted; logged once)", why);
}

int WebServer::onConnect(const mg_connection* conn, void*) {
  WebServer& s = *self(conn);
  const std::string token = queryValue(mg_get_request_info(conn)->query_string, "token");
  std::lock_guard lock(s.mutex_);
  std::string why;
  if (!sameToken(token, s.token_)) why = token.empty() ? "a connection without the token" : "a wrong token";
  else if ((int)s.viewers_.size() >= kMaxViewers) why = "more than " + std::to_string(kMaxViewers) + " viewers";
  if (why.empty()) return 0;
  ++s.counters_.refused;
  if (std::find(s.logged_.begin(), s.logged_.end(), why) == s.logged_.end()) {
    s.logged_.push_back(why);
    spdlog::warn("web view: refused {} (counted; logged once)", why);
  }
  return 1;
}

void WebServer::onReady(mg_connection* conn, void*) {
  WebServer& s = *self(conn);
  auto v = std::make_shared<Viewer>();
  v->conn = conn;
  v->connected_at = std::chrono::steady_clock::now();
  // The page's number for its load: up to 9 digits (anything else: none; it only labels input).
  if (const std::string page = queryValue(mg_get_request_info(conn)->query_string, "page");
      !page.empty() && page.size() <= 9 && page.find_first_not_of("0123456789") == std::string::npos)
    v->page = (uint32_t)std::stoul(page);
  std::lock_guard lock(s.mutex_);
  v->pending = s.latest_;  // a viewer that (re)connects sees the current frame at once
  mg_set_user_connection_data(conn, v.get());
  v->sender = std::thread(sendLoop, std::ref(*v), std::ref(s.sent_), std::ref(s.cut_short_));
  s.viewers_.push_back(v);
  ++s.counters_.connections;
  if (s.on_viewer_) s.on_viewer_();
}

int WebServer::onData(mg_connection* conn, int bits, char* data, size_t size, void*) {
  WebServer& s = *self(conn);
  const int opcode = bits & 0x0f;
  if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
  if (opcode == MG_WEBSOCKET_OPCODE_PING || opcode == MG_WEBSOCKET_OPCODE_PONG) return 1;
  auto* v = static_cast<Viewer*>(mg_get_user_connection_data(conn));
  const auto arrived = std::chrono::steady_clock::now();
  std::lock_guard lock(s.mutex_);
  if (v) {
    std::lock_guard vl(v->m);
    if (v->dead) return 0;  // half a frame went out: close, the page reconnects
  }
  if (size > kMaxMessage) {
    s.badMessage("a message larger than " + std::to_string(kMaxMessage) + " bytes (connection closed)");
    return 0;
  }
  if (opcode != MG_WEBSOCKET_OPCODE_TEXT) {
    s.badMessage("a binary or continued message");
    return 1;
  }
  const auto msg = nlohmann::json::parse(data, data + size, nullptr, false);
  const std::string type = msg.is_object() && msg.contains("t") && msg["t"].is_string() ? msg["t"].get<std::string>() : "";
  if (msg.is_discarded()) {
    s.badMessage("a message that is not JSON");
  } else if (type == "ack") {
    const uint64_t id = msg.contains("id") && msg["id"].is_number_unsigned() ? msg["id"].get<uint64_t>() : UINT64_MAX;
    bool known = false;
    if (v) {
      std::lock_guard vl(v->m);
      const auto it = std::find_if(v->unacked.begin(), v->unacked.end(), [&](const auto& f) { return f.id == id; });
      known = it != v->unacked.end();
      // A frame presented while this viewer watched: how long until it was on the page.
      if (known && it->shown_at >= v->connected_at) {
        auto& times = it->lossless ? s.lossless_ms_ : s.moving_ms_;
        times.push_back(std::chrono::duration<double, std::milli>(arrived - it->shown_at).count());
        if (times.size() > 1000) times.pop_front();
      }
      if (known) v->unacked.erase(v->unacked.begin(), it + 1);  // and any older ones it passed
      v->cv.notify_one();
    }
    if (!known) s.badMessage("an acknowledgement of a frame this connection has not been sent");
  } else if (type == "drag" || type == "release" || type == "wheel" || type == "key") {
    if (const std::string why = badInput(msg, type); !why.empty()) s.badMessage(why);
    else if (s.input_.size() < kMaxQueuedInput)
      s.input_.push_back({msg, arrived, v ? v->page : 0u, msg.contains("n") ? msg["n"].get<uint64_t>() : 0u});
    else s.badMessage("input beyond " + std::to_string(kMaxQueuedInput) + " messages before the display read them");
  } else {
    s.badMessage("an unknown message type");
  }
  return 1;
}

void WebServer::onClose(const mg_connection* conn, void*) {
  WebServer& s = *self(conn);
  auto* raw = static_cast<Viewer*>(mg_get_user_connection_data(conn));
  std::shared_ptr<Viewer> v;
  {
    std::lock_guard lock(s.mutex_);
    auto it = std::find_if(s.viewers_.begin(), s.viewers_.end(), [&](auto& p) { return p.get() == raw; });
    if (it == s.viewers_.end()) return;
    v = *it;
    s.viewers_.erase(it);
  }
  {
    std::lock_guard vl(v->m);
    v->closing = true;
    v->cv.notify_one();
  }
  if (v->sender.joinable()) v->sender.join();
}

int WebServer::onRequest(mg_connection* conn, void*) {
  const mg_request_info* ri = mg_get_request_info(conn);
  const std::string path = ri->local_uri ? ri->local_uri : "";
  const WebAsset* asset = nullptr;
  for (const WebAsset& a : webAssets())
    if (path == a.path || (path == "/" && std::string(a.path) == "/index.html")) asset = &a;
  if (!asset || std::strcmp(ri->request_method, "GET") != 0) {
    mg_send_http_error(conn, 404, "%s", "not found: the web view serves / and its script only");
    return 404;
  }
  mg_send_http_ok(conn, asset->mime, (long long)asset->size);
  mg_write(conn, asset->data, asset->size);
  return 200;
}

int WebServer::onHttpError(mg_connection* conn, int status, const char*) {
  WebServer& s = *self(conn);
  std::lock_guard lock(s.mutex_);
  ++s.counters_.bad_requests;
  const std::string why = "HTTP " + std::to_string(status);
  if (std::find(s.logged_.begin(), s.logged_.end(), why) == s.logged_.end()) {
    s.logged_.push_back(why);
    spdlog::warn("web view: a request ended in {} (unknown path or not HTTP; counted; logged once)", why);
  }
  return 1;  // civetweb's own error page
}

}  // namespace tessera::display
