// A stage's data socket — pieces at a compositor, strips at the display — as a ROUTER that
// takes messages only from the members the master's Roster names, recognised by the routing
// id of their connection (MemberFilter). Multi-part junk is drained and dropped; everything
// refused is counted and logged (rate-limited) through the stage's DropCounter.
// Single-threaded (the stage's loop).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "common/net/log.h"
#include "common/net/member_filter.h"
#include "common/wire/protocol.h"

namespace tessera {

class DataInbox {
 public:
  // `senders`: the roles that may send here; `max_message`: ZMQ_MAXMSGSIZE; `max_waiting_bytes`:
  // the quarantine for messages that overtake the Roster naming their sender.
  DataInbox(zmq::context_t& ctx, std::vector<proto::Role> senders, int64_t max_message, size_t max_waiting_bytes);
  void bind(const std::string& endpoint);
  zmq::socket_t& socket() { return socket_; }

  struct Message {
    uint32_t rank = 0;  // the sender's rank in the roster: check it against what the message claims
    zmq::message_t body;
    proto::Role role = proto::Role::Renderer;  // and its role
  };
  // Up to `max` messages from members (non-blocking).
  std::vector<Message> receive(DropCounter& drops, int max = 256);
  // Installs a newer roster; returns the held messages it admits (the others are dropped).
  std::vector<Message> setRoster(const proto::Roster& roster, DropCounter& drops);
  uint32_t rosterEpoch() const { return filter_.epoch(); }

 private:
  zmq::socket_t socket_;
  MemberFilter filter_;
};

}  // namespace tessera
