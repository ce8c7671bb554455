// libwebsockets callbacks of the web view. See web_server.h. Every callback runs on the
// service thread; publish() and the display's calls come from other threads, so the state is
// under mutex_ and publish() wakes the service thread with lws_cancel_service.
#include "display/web_server.h"

#include <libwebsockets.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "display/web_assets.h"

namespace tessera::display {

struct WebServer::Viewer {
  struct Sent {
    uint64_t id;
    bool lossless;
    std::chrono::steady_clock::time_point shown_at;
  };
  lws* wsi = nullptr;
  uint32_t page = 0;  // the page's number for its load (0: none given)
  std::chrono::steady_clock::time_point connected_at;
  std::shared_ptr<const WebFrame> pending;  // the newest frame not yet sent (publish() sets it)
  // The rest is the service thread's alone.
  std::deque<Sent> unacked;                 // sent and not acknowledged yet
  std::shared_ptr<const WebFrame> sending;  // the frame going out, a piece per writeable callback
  size_t offset = 0;                        // of its bytes written so far
  std::string in;                           // the message being received
  bool in_binary = false;
};

namespace {

constexpr size_t kMaxQueuedInput = 1024;  // input messages between two display polls
constexpr int kDrainSeconds = 5;          // a viewer that takes no piece of a frame for this long is closed
// A frame goes out in pieces of this size, one per writeable callback: the drain timeout is
// per piece (a slow link that keeps reading is never cut off), the display's pings go out
// between pieces, and the server holds one piece per viewer, not a copy of the frame.
constexpr size_t kPiece = 64 * 1024;

// What a connection is to us: a request for the page or its script, or a viewer.
struct Session {
  const WebAsset* asset;
  WebServer::Viewer* viewer;
};

bool sameToken(const std::string& a, const std::string& b) {
  unsigned diff = a.size() != b.size();
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) diff |= (unsigned)(a[i] ^ b[i]);
  return diff == 0;  // time independent of where they differ
}

std::string urlArg(lws* wsi, const char* name) {
  char buf[256];
  const char* v = lws_get_urlarg_by_name(wsi, name, buf, sizeof buf);
  return v ? std::string(v) : std::string();
}

// Why a viewer's input message is unusable ("" when it is fine): numbers finite and bounded.
std::string badInput(const nlohmann::json& msg, const std::string& type) {
  auto number = [&](const char* key, double limit) {
    return msg.contains(key) && msg[key].is_number() && std::abs(msg[key].get<double>()) <= limit;
  };
  if ((type == "drag" || type == "window") && !(number("dx", 1e4) && number("dy", 1e4)))
    return "a " + type + " drag without numbers dx, dy within 10000";
  if (type == "wheel" && !number("notches", 100)) return "a wheel without a number of notches within 100";
  if (type == "key" && !(msg.contains("key") && msg["key"].is_string())) return "a key without a key";
  // The keys the view steers with (viewer.js sends no others): any other is refused, not
  // dropped unseen (found by review).
  static const std::set<std::string> keys{"1", "2", "3", " ", "ArrowRight", "ArrowLeft", "Home", "End", "r"};
  if (type == "key" && !keys.count(msg["key"].get<std::string>()))
    return "an unknown key (1, 2, 3, r, Space, ArrowLeft, ArrowRight, Home, End)";
  if (msg.contains("n") && !msg["n"].is_number_unsigned()) return "an input number n that is not a whole number";
  return "";
}

void logLibwebsockets(int level, const char* line) {
  std::string s(line);
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  if (level & LLL_ERR) spdlog::warn("web view (libwebsockets): {}", s);
}

}  // namespace

struct WebCallbacks {
  static int callback(lws* wsi, lws_callback_reasons reason, void* user, void* in, size_t len);
  static int http(WebServer& s, lws* wsi, Session& session, const char* uri);
  static int httpBody(lws* wsi, Session& session);
  static void established(WebServer& s, lws* wsi, Session& session);
  static int writeable(WebServer& s, lws* wsi, WebServer::Viewer& v);
  static int receive(WebServer& s, lws* wsi, WebServer::Viewer& v, const char* data, size_t size);
  static void message(WebServer& s, WebServer::Viewer& v, std::chrono::steady_clock::time_point arrived);
  static void closed(WebServer& s, WebServer::Viewer* v);
  static void logOnce(WebServer& s, const std::string& what);
};

WebServer::WebServer(const std::string& given, std::string token) : token_(std::move(token)) {
  if (token_.size() > 200) throw std::runtime_error("the web view's token is longer than 200 characters");
  const WebAddress where = parseWebAddress(given);
  host_ = where.host;
  const std::string address = host_ + ":" + std::to_string(where.port);
  lws_set_log_level(LLL_ERR, &logLibwebsockets);
  static const lws_protocols protocols[] = {
      {"tessera", &WebCallbacks::callback, sizeof(Session), kMaxMessage, 0, nullptr, 0}, {nullptr, nullptr, 0, 0, 0, nullptr, 0}};
  // Pings after 3 s without traffic: a viewer whose link died (a laptop asleep, a dropped NAT
  // entry) is closed after 10 s instead of holding its slot until TCP gives up.
  static const lws_retry_bo_t idle = {nullptr, 0, 0, 3, 10, 0};
  lws_context_creation_info info{};
  info.port = where.port;
  info.iface = host_.c_str();
  info.protocols = protocols;
  info.user = this;
  info.retry_and_idle_policy = &idle;
  info.options = LWS_SERVER_OPTION_VALIDATE_UTF8;
  info.fd_limit_per_thread = 256;  // connections at once (viewers, page loads, strangers)
  ctx_ = lws_create_context(&info);
  if (!ctx_) throw std::runtime_error("--web " + address + ": cannot listen there (in use, or not this host's address?)");
  port_ = lws_get_vhost_listen_port(lws_get_vhost_by_name(ctx_, "default"));
  service_ = std::thread([this] {
    while (!stop_) lws_service(ctx_, 0);
  });
}

WebServer::~WebServer() {
  stop_ = true;
  lws_cancel_service(ctx_);
  service_.join();
  lws_context_destroy(ctx_);  // closes every connection (their close callbacks run here)
}

std::string WebServer::url() const { return "http://" + host_ + ":" + std::to_string(port_) + "/#" + token_; }

void WebServer::publish(std::shared_ptr<const WebFrame> frame) {
  {
    std::lock_guard lock(mutex_);
    latest_ = frame;
    for (auto& v : viewers_) {
      if (v->pending) ++counters_.frames_replaced;
      v->pending = frame;
    }
  }
  lws_cancel_service(ctx_);  // the service thread asks each viewer's connection to write
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
  c.frames_sent = sent_;
  c.cut_short = cut_short_;
  c.lossless_ms.assign(lossless_ms_.begin(), lossless_ms_.end());
  c.moving_ms.assign(moving_ms_.begin(), moving_ms_.end());
  return c;
}

void WebServer::badMessage(const std::string& why) {  // with mutex_ held
  ++counters_.bad_messages;
  WebCallbacks::logOnce(*this, "refused a viewer message: " + why);
}

void WebCallbacks::logOnce(WebServer& s, const std::string& what) {  // with mutex_ held
  if (std::find(s.logged_.begin(), s.logged_.end(), what) != s.logged_.end()) return;
  s.logged_.push_back(what);
  spdlog::warn("web view: {} (counted; logged once)", what);
}

int WebCallbacks::callback(lws* wsi, lws_callback_reasons reason, void* user, void* in, size_t len) {
  auto* s = static_cast<WebServer*>(lws_context_user(lws_get_context(wsi)));
  auto* session = static_cast<Session*>(user);
  switch (reason) {
    case LWS_CALLBACK_SERVER_NEW_CLIENT_INSTANTIATED: {
      std::lock_guard lock(s->mutex_);
      s->unrequested_.insert(wsi);
      return 0;
    }
    case LWS_CALLBACK_WSI_DESTROY: {  // a connection that never made a request: garbage, or nothing
      std::lock_guard lock(s->mutex_);
      if (s->unrequested_.erase(wsi)) {
        ++s->counters_.bad_requests;
        logOnce(*s, "refused a connection that sent no HTTP request (not HTTP, or nothing: browsers' unused "
                    "pre-connections count too)");
      }
      return 0;
    }
    case LWS_CALLBACK_HTTP:
      return http(*s, wsi, *session, static_cast<const char*>(in));
    case LWS_CALLBACK_HTTP_WRITEABLE:
      return httpBody(wsi, *session);
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION: {
      const std::string token = urlArg(wsi, "token=");
      std::lock_guard lock(s->mutex_);
      s->unrequested_.erase(wsi);
      std::string why;
      if (!sameToken(token, s->token_)) why = token.empty() ? "a connection without the token" : "a wrong token";
      else if ((int)s->viewers_.size() >= WebServer::kMaxViewers)
        why = "more than " + std::to_string(WebServer::kMaxViewers) + " viewers";
      if (why.empty()) return 0;
      ++s->counters_.refused;
      logOnce(*s, "refused " + why);
      return 1;
    }
    case LWS_CALLBACK_ESTABLISHED:
      established(*s, wsi, *session);
      return 0;
    case LWS_CALLBACK_SERVER_WRITEABLE:
      return session->viewer ? writeable(*s, wsi, *session->viewer) : 0;
    case LWS_CALLBACK_RECEIVE:
      return session->viewer ? receive(*s, wsi, *session->viewer, static_cast<const char*>(in), len) : -1;
    case LWS_CALLBACK_CLOSED:
      closed(*s, session->viewer);
      session->viewer = nullptr;
      return 0;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED: {  // publish(): new frames to send
      std::lock_guard lock(s->mutex_);
      for (auto& v : s->viewers_)
        if (v->pending) lws_callback_on_writable(v->wsi);
      return 0;
    }
    default:
      return lws_callback_http_dummy(wsi, reason, user, in, len);
  }
}

int WebCallbacks::http(WebServer& s, lws* wsi, Session& session, const char* uri) {
  {
    std::lock_guard lock(s.mutex_);
    s.unrequested_.erase(wsi);
  }
  const std::string path = uri ? uri : "";
  const bool get = lws_hdr_total_length(wsi, WSI_TOKEN_GET_URI) > 0;
  session.asset = nullptr;
  for (const WebAsset& a : webAssets())
    if (path == a.path || (path == "/" && std::string(a.path) == "/index.html")) session.asset = &a;
  if (!session.asset || !get) {
    {
      std::lock_guard lock(s.mutex_);
      ++s.counters_.bad_requests;
      logOnce(s, "refused a request for anything but the page and its script (HTTP 404)");
    }
    if (lws_return_http_status(wsi, HTTP_STATUS_NOT_FOUND, "not found: the web view serves / and its script only"))
      return -1;
    return lws_http_transaction_completed(wsi) ? -1 : 0;
  }
  unsigned char buf[LWS_PRE + 512];
  unsigned char *start = buf + LWS_PRE, *p = start, *end = buf + sizeof buf - 1;
  if (lws_add_http_common_headers(wsi, HTTP_STATUS_OK, session.asset->mime, session.asset->size, &p, end) ||
      lws_finalize_write_http_header(wsi, start, &p, end))
    return 1;
  lws_callback_on_writable(wsi);
  return 0;
}

int WebCallbacks::httpBody(lws* wsi, Session& session) {
  if (!session.asset) return -1;
  std::vector<unsigned char> body(LWS_PRE + session.asset->size);
  std::memcpy(body.data() + LWS_PRE, session.asset->data, session.asset->size);
  session.asset = nullptr;
  if (lws_write(wsi, body.data() + LWS_PRE, body.size() - LWS_PRE, LWS_WRITE_HTTP_FINAL) < 0) return -1;
  return lws_http_transaction_completed(wsi) ? -1 : 0;
}

void WebCallbacks::established(WebServer& s, lws* wsi, Session& session) {
  auto v = std::make_shared<WebServer::Viewer>();
  v->wsi = wsi;
  v->connected_at = std::chrono::steady_clock::now();
  // The page's number for its load: up to 9 digits (anything else: none; it only labels input).
  if (const std::string page = urlArg(wsi, "page=");
      !page.empty() && page.size() <= 9 && page.find_first_not_of("0123456789") == std::string::npos)
    v->page = (uint32_t)std::stoul(page);
  session.viewer = v.get();
  std::lock_guard lock(s.mutex_);
  v->pending = s.latest_;  // a viewer that (re)connects sees the current frame at once
  s.viewers_.push_back(v);
  ++s.counters_.connections;
  spdlog::info("web view: a viewer connected ({} watching)", s.viewers_.size());
  if (s.on_viewer_) s.on_viewer_();
  if (v->pending) lws_callback_on_writable(wsi);
}

// The next piece of the frame going out; else the newest frame, when fewer than kMaxUnacked
// are unacknowledged. What the socket does not take libwebsockets keeps, and calls here again
// once it has sent it.
int WebCallbacks::writeable(WebServer& s, lws* wsi, WebServer::Viewer& v) {
  if (!v.sending) {
    std::lock_guard lock(s.mutex_);
    if (!v.pending || (int)v.unacked.size() >= WebServer::kMaxUnacked) {
      lws_set_timeout(wsi, NO_PENDING_TIMEOUT, 0);
      return 0;
    }
    v.sending = std::move(v.pending);
    v.pending.reset();
    v.offset = 0;
    v.unacked.push_back({v.sending->id, v.sending->lossless, v.sending->shown_at});
    ++s.sent_;
  }
  const auto& bytes = v.sending->message;
  const size_t n = std::min(kPiece, bytes.size() - v.offset);
  unsigned char piece[LWS_PRE + kPiece];
  std::memcpy(piece + LWS_PRE, bytes.data() + v.offset, n);
  const bool first = v.offset == 0, last = v.offset + n == bytes.size();
  if (lws_write(wsi, piece + LWS_PRE, n, (lws_write_protocol)lws_write_ws_flags(LWS_WRITE_BINARY, first, last)) < 0)
    return -1;
  v.offset += n;
  if (last) v.sending.reset();
  lws_set_timeout(wsi, PENDING_TIMEOUT_USER_OK, kDrainSeconds);  // cleared once nothing is left to send
  lws_callback_on_writable(wsi);
  return 0;
}

int WebCallbacks::receive(WebServer& s, lws* wsi, WebServer::Viewer& v, const char* data, size_t size) {
  const auto arrived = std::chrono::steady_clock::now();
  lws_validity_confirmed(wsi);  // the viewer is there: no ping needed to know it
  if (lws_is_first_fragment(wsi)) {
    v.in.clear();
    v.in_binary = lws_frame_is_binary(wsi);
  }
  std::lock_guard lock(s.mutex_);
  if (v.in.size() + size > WebServer::kMaxMessage) {
    s.badMessage("a message larger than " + std::to_string(WebServer::kMaxMessage) + " bytes (connection closed)");
    return -1;
  }
  v.in.append(data, size);
  if (lws_is_final_fragment(wsi) && lws_remaining_packet_payload(wsi) == 0) message(s, v, arrived);
  return 0;
}

void WebCallbacks::message(WebServer& s, WebServer::Viewer& v, std::chrono::steady_clock::time_point arrived) {
  if (v.in_binary) return s.badMessage("a binary message");
  const auto msg = nlohmann::json::parse(v.in, nullptr, false);
  const std::string type = msg.is_object() && msg.contains("t") && msg["t"].is_string() ? msg["t"].get<std::string>() : "";
  if (msg.is_discarded()) {
    s.badMessage("a message that is not JSON");
  } else if (type == "ack") {
    const uint64_t id = msg.contains("id") && msg["id"].is_number_unsigned() ? msg["id"].get<uint64_t>() : UINT64_MAX;
    const auto it = std::find_if(v.unacked.begin(), v.unacked.end(), [&](const auto& f) { return f.id == id; });
    if (it == v.unacked.end()) return s.badMessage("an acknowledgement of a frame this connection has not been sent");
    // A frame presented while this viewer watched: how long until it was on the page.
    if (it->shown_at >= v.connected_at) {
      auto& times = it->lossless ? s.lossless_ms_ : s.moving_ms_;
      times.push_back(std::chrono::duration<double, std::milli>(arrived - it->shown_at).count());
      if (times.size() > 1000) times.pop_front();
    }
    v.unacked.erase(v.unacked.begin(), it + 1);  // and any older ones it passed
    if (v.pending) lws_callback_on_writable(v.wsi);
  } else if (type == "drag" || type == "window" || type == "release" || type == "wheel" || type == "key") {
    if (const std::string why = badInput(msg, type); !why.empty()) s.badMessage(why);
    else if (s.input_.size() < kMaxQueuedInput)
      s.input_.push_back({msg, arrived, v.page, msg.contains("n") ? msg["n"].get<uint64_t>() : 0u});
    else s.badMessage("input beyond " + std::to_string(kMaxQueuedInput) + " messages before the display read them");
  } else {
    s.badMessage("an unknown message type");
  }
}

void WebCallbacks::closed(WebServer& s, WebServer::Viewer* v) {
  if (!v) return;
  std::lock_guard lock(s.mutex_);
  if (v->sending) ++s.cut_short_;  // closed in the middle of a frame: it stopped reading, or left
  auto it = std::find_if(s.viewers_.begin(), s.viewers_.end(), [&](auto& p) { return p.get() == v; });
  if (it != s.viewers_.end()) s.viewers_.erase(it);
  if (s.viewers_.empty()) s.latest_.reset();  // not encoded while nobody watched: the next viewer gets a new one
  spdlog::info("web view: a viewer left ({} watching)", s.viewers_.size());
}

}  // namespace tessera::display
