#include "common/net/transport.h"

#include <algorithm>

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

int64_t maxPixelMessageBytes(int width, int height) {
  const int64_t pixels = int64_t(std::max(width, 1)) * std::max(height, 1);
  return 34 * pixels + (64 << 10);
}

}  // namespace tessera
