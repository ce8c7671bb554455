#include "common/net/transport.h"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "common/net/curve.h"

namespace tessera {

bool sendBytes(zmq::socket_t& s, std::vector<std::byte>&& bytes, bool more, bool dontwait) {
  auto* owned = new std::vector<std::byte>(std::move(bytes));
  zmq::message_t msg(owned->data(), owned->size(),
                     [](void*, void* hint) { delete static_cast<std::vector<std::byte>*>(hint); }, owned);
  zmq::send_flags flags = zmq::send_flags::none;
  if (more) flags = flags | zmq::send_flags::sndmore;
  if (dontwait) flags = flags | zmq::send_flags::dontwait;
  try {
    return s.send(msg, flags).has_value();
  } catch (const zmq::error_t&) {
    return false;  // context terminated during shutdown
  }
}

void pollFor(zmq::pollitem_t* items, size_t n, std::chrono::milliseconds timeout) {
  try {
    zmq::poll(items, n, timeout);
  } catch (const zmq::error_t& e) {
    if (e.num() != EINTR) throw;
    for (size_t i = 0; i < n; ++i) items[i].revents = 0;
  }
}

zmq::socket_t makeSocket(zmq::context_t& ctx, zmq::socket_type type, int64_t max_message_bytes) {
  zmq::socket_t s(ctx, type);
  s.set(zmq::sockopt::maxmsgsize, max_message_bytes);
  s.set(zmq::sockopt::linger, 0);
  s.set(zmq::sockopt::sndhwm, 64);
  s.set(zmq::sockopt::rcvhwm, 64);
  return s;
}

zmq::socket_t connectDataSender(zmq::context_t& ctx, const std::string& endpoint, const std::string& identity) {
  zmq::socket_t s = makeSocket(ctx, zmq::socket_type::dealer);
  s.set(zmq::sockopt::routing_id, identity);
  s.set(zmq::sockopt::linger, 1000);
  s.set(zmq::sockopt::sndtimeo, (int)kDataSendTimeout.count());
  connectTo(s, endpoint);
  return s;
}

int64_t maxPixelMessageBytes(int width, int height) {
  const int64_t pixels = int64_t(std::max(width, 1)) * std::max(height, 1);
  return 34 * pixels + (64 << 10);
}

void claimIpcEndpoint(const std::string& endpoint) {
  if (endpoint.rfind("ipc://", 0) != 0) return;
  const std::string path = endpoint.substr(6);
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0 || !S_ISSOCK(st.st_mode)) return;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) return;  // ZeroMQ's bind reports this itself
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  const bool live = connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  if (!live) {
    spdlog::info("removed {}: a socket file left by a farm that is gone", path);
    std::filesystem::remove(path);
    return;
  }
  std::ifstream farm(std::filesystem::path(path).parent_path() / "farm");
  std::string owner;
  std::getline(farm, owner);
  throw std::runtime_error(endpoint + " is in use by a live farm" + (owner.empty() ? "" : " (" + owner + ")") +
                           ": stop it, or give this farm other endpoints (TESSERA_ENDPOINTS)");
}

FarmNote::FarmNote(const std::string& endpoint_base, const std::string& text) {
  if (endpoint_base.rfind("ipc://", 0) != 0) return;
  path_ = (std::filesystem::path(endpoint_base.substr(6)) / "farm").string();
  std::ofstream(path_) << text << '\n';
}

FarmNote::~FarmNote() {
  std::error_code ignored;
  if (!path_.empty()) std::filesystem::remove(path_, ignored);
}

std::optional<Routed> receiveRouted(zmq::socket_t& router) {
  zmq::message_t id;
  if (!router.recv(id, zmq::recv_flags::dontwait)) return std::nullopt;
  Routed m;
  m.identity = id.to_string();
  if (!id.more()) return m;
  m.has_body = router.recv(m.body, zmq::recv_flags::dontwait).has_value();
  for (bool more = m.has_body && m.body.more(); more;) {
    zmq::message_t part;
    if (!router.recv(part, zmq::recv_flags::dontwait)) break;
    more = part.more();
    m.extra = true;
  }
  return m;
}

}  // namespace tessera
