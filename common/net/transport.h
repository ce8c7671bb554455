// Thin helpers over ZeroMQ: zero-copy sends of encoded messages and byte views of
// received ones. Every stage's run() takes the zmq::context_t, so a whole farm can also
// run inside one process over inproc:// (tests), or over ipc:// / tcp:// for real.
#pragma once
#include <chrono>
#include <cstddef>
#include <span>
#include <vector>

#include <zmq.hpp>

namespace tessera {

// Moves `bytes` into ZeroMQ without copying (freed by ZeroMQ after the send).
// Returns false if the socket would block (with dontwait) or was closed.
bool sendBytes(zmq::socket_t& s, std::vector<std::byte>&& bytes, bool more = false, bool dontwait = false);

inline std::span<const std::byte> view(const zmq::message_t& m) {
  return {static_cast<const std::byte*>(m.data()), m.size()};
}

// zmq::poll that treats a signal (EINTR) as "nothing ready": the caller's loop then
// sees its stop flag. Other errors propagate.
void pollFor(zmq::pollitem_t* items, size_t n, std::chrono::milliseconds timeout);

// A socket with the options every Tessera socket wants: no linger at close, and bounded
// queues so no queue grows without bound.
zmq::socket_t makeSocket(zmq::context_t& ctx, zmq::socket_type type);

}  // namespace tessera
