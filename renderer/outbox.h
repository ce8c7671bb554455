// A renderer's data sockets: one per receiver (a compositor, a swap partner, the display),
// connected on first use and closed once the frames no longer name that receiver.
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "common/net/log.h"
#include "common/wire/protocol.h"

namespace tessera::renderer {

class Outbox {
 public:
  Outbox(zmq::context_t& ctx, std::string identity) : ctx_(ctx), identity_(std::move(identity)) {}

  // Sends a part to `endpoint`. A receiver that stopped reading (its process dead or
  // stopped, its link cut) lets this socket's own queue fill; the send then gives up after
  // kDataSendTimeout and the part is dropped and counted, instead of blocking the renderer
  // for good: the master re-issues the frame, and a replacement receiver has an endpoint of
  // its own.
  void send(const std::string& endpoint, std::vector<std::byte>&& bytes);

  // Peers come and go (a restarted renderer has a new swap port): sockets to endpoints that
  // frame p does not name would retry a dead address forever, so they are closed.
  void keepOnly(const proto::FrameParams& p, const proto::SortLastWork& work);

  uint64_t unsent() const { return unsent_.total(); }

 private:
  zmq::context_t& ctx_;
  std::string identity_;
  std::map<std::string, zmq::socket_t> pushes_;
  DropCounter unsent_;  // parts not sent (apart from the stage's drops, which count by sender)
};

}  // namespace tessera::renderer
