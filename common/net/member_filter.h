// Which peers may send on a stage's data socket: the members named by the master's latest
// Roster, recognised by the ZeroMQ routing id of their data connection, never by a field
// they write themselves. A new member's first message can overtake the Roster that names it
// (they travel on different connections), so messages from an identity the roster does not
// name wait in a small bounded quarantine until the next Roster admits or drops them.
// Single-threaded (the stage's loop).
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "common/wire/protocol.h"

namespace tessera {

class MemberFilter {
 public:
  // `senders`: the roles allowed on this socket (renderers at a compositor; compositors, and
  // renderers with a binary swap's bands, at the display). The quarantine holds at most
  // `max_waiting` messages and `max_waiting_bytes`.
  MemberFilter(std::vector<proto::Role> senders, size_t max_waiting, size_t max_waiting_bytes);

  struct Sender {
    proto::Role role;
    uint32_t rank;
  };
  // Who a routing id is in the current roster, if a member of an allowed role.
  std::optional<Sender> senderOf(const std::string& identity) const;

  struct Held {
    std::string identity;
    zmq::message_t body;
  };
  // A message from an identity the roster does not name: kept (true) or, with the quarantine
  // full, refused (false: the caller drops and counts it).
  bool hold(std::string identity, zmq::message_t&& body);
  // Installs a newer roster (older ones are ignored) and returns the held messages it admits;
  // `dropped` counts the held messages it does not admit.
  std::vector<Held> setRoster(const proto::Roster& roster, uint64_t& dropped);

  uint32_t epoch() const { return epoch_; }
  size_t waiting() const { return held_.size(); }

 private:
  std::vector<proto::Role> senders_;
  size_t max_waiting_, max_waiting_bytes_, held_bytes_ = 0;
  bool have_roster_ = false;
  uint32_t epoch_ = 0;
  std::map<std::string, Sender> members_;
  std::deque<Held> held_;
};

}  // namespace tessera
