// Member-only data socket (see data_inbox.h).
#include "common/net/data_inbox.h"

#include "common/net/curve.h"
#include "common/net/transport.h"

namespace tessera {
namespace {

// Quarantine length: a new member's first frames of pieces at most (renderers send one piece
// per compositor per frame; a few frames in flight).
constexpr size_t kMaxWaitingMessages = 64;

// The epoch a pixel message says it was made for (all three start their payload with it),
// or 0 when it is not a well-formed pixel message.
uint32_t claimedEpoch(const zmq::message_t& body) {
  auto h = proto::decodeHeader(view(body));
  if (!h || !(h->type == proto::Type::Piece || h->type == proto::Type::Strips || h->type == proto::Type::Framebuffer) ||
      body.size() < proto::kHeaderSize + 4)
    return 0;
  const auto* p = static_cast<const uint8_t*>(body.data()) + proto::kHeaderSize;
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

}  // namespace

DataInbox::DataInbox(zmq::context_t& ctx, std::vector<proto::Role> senders, int64_t max_message, size_t max_waiting_bytes)
    : socket_(makeSocket(ctx, zmq::socket_type::router, max_message)),
      filter_(std::move(senders), kMaxWaitingMessages, max_waiting_bytes) {
  socket_.set(zmq::sockopt::rcvhwm, 0);  // bounded by the master's frame window
}

void DataInbox::bind(const std::string& endpoint) { bindTo(socket_, endpoint); }

std::vector<DataInbox::Message> DataInbox::receive(DropCounter& drops, int max) {
  std::vector<Message> out;
  for (int i = 0; i < max; ++i) {
    auto m = receiveRouted(socket_);
    if (!m) break;
    if (!m->has_body) continue;
    std::string identity = std::move(m->identity);
    zmq::message_t body = std::move(m->body);
    const bool extra = m->extra;
    if (auto sender = filter_.senderOf(identity)) {
      if (extra) drops.drop(sender->rank, "multi-part message");
      else out.push_back({sender->rank, std::move(body), sender->role});
    } else if (extra || claimedEpoch(body) <= filter_.epoch() || !filter_.hold(std::move(identity), std::move(body))) {
      // Only a message of a newer epoch than the roster may come from a member the master
      // has just announced (its Roster travels on another connection): that one waits.
      drops.drop(~0u, "refused peer: not a member of this farm's current roster");
    }
  }
  return out;
}

std::vector<DataInbox::Message> DataInbox::setRoster(const proto::Roster& roster, DropCounter& drops) {
  uint64_t dropped = 0;
  std::vector<Message> out;
  for (auto& h : filter_.setRoster(roster, dropped)) {
    const auto sender = *filter_.senderOf(h.identity);
    out.push_back({sender.rank, std::move(h.body), sender.role});
  }
  for (uint64_t i = 0; i < dropped; ++i) drops.drop(~0u, "refused peer: not named by the roster");
  return out;
}

}  // namespace tessera
