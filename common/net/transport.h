// Thin helpers over ZeroMQ: zero-copy sends of encoded messages and byte views of
// received ones. Every stage's run() takes the zmq::context_t, so a whole farm can also
// run inside one process over inproc:// (tests), or over ipc:// / tcp:// for real.
#pragma once
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <zmq.hpp>

namespace tessera {

// Moves `bytes` into ZeroMQ without copying (freed by ZeroMQ after the send).
// Returns false if the socket would block (with dontwait), its send timeout ran out, or it
// was closed.
bool sendBytes(zmq::socket_t& s, std::vector<std::byte>&& bytes, bool more = false, bool dontwait = false);

// How long a stage's send of frame data may wait for room in its own queue to a receiver (64
// messages, full only when the receiver stopped reading: its process dead or stopped, its link
// cut): the master's shortest frame deadline, after which it re-issues the frame anyway.
inline constexpr std::chrono::milliseconds kDataSendTimeout{3000};

// A stage's socket for frame data to one receiver (a compositor, a swap partner, the
// display), connected: a DEALER that names itself `identity` (receivers admit it by this),
// gives its last parts a second to leave at shutdown, and gives up a send after
// kDataSendTimeout rather than block the stage for good on a receiver that stopped reading.
zmq::socket_t connectDataSender(zmq::context_t& ctx, const std::string& endpoint, const std::string& identity);

inline std::span<const std::byte> view(const zmq::message_t& m) {
  return {static_cast<const std::byte*>(m.data()), m.size()};
}

// One message from a ROUTER socket, without waiting: nothing when none is queued. `body` is
// its first part after the routing id (empty when a peer sent no routing id, which a ROUTER
// never does); parts beyond it are a peer's junk: read, dropped, and `extra` says so.
struct Routed {
  std::string identity;
  zmq::message_t body;
  bool has_body = false, extra = false;
};
std::optional<Routed> receiveRouted(zmq::socket_t& router);

// zmq::poll that treats a signal (EINTR) as "nothing ready": the caller's loop then
// sees its stop flag. Other errors propagate.
void pollFor(zmq::pollitem_t* items, size_t n, std::chrono::milliseconds timeout);

// A socket with the options every Tessera socket wants: no linger at close, and bounded
// queues so no queue grows without bound. An input socket also passes the largest message
// it can legitimately receive: ZeroMQ then refuses longer ones while reading their size
// (it drops that peer's connection, so they are never seen nor counted by the stage).
// -1 = no limit.
zmq::socket_t makeSocket(zmq::context_t& ctx, zmq::socket_type type, int64_t max_message_bytes = -1);

// The largest pixel message (Piece, Framebuffer, Strips) for a width x height image.
// Largest raw payload: a Piece of the whole image in rgba32f, 16 bytes a pixel. Rgba8
// framebuffers and strip streams (4 bytes a pixel) add 2 header pixels per strip row and,
// sort-first, shelf-packing gaps; doubling the rgba32f size covers them with room to
// spare (8x the image's pixels at rgba8). Codecs expand incompressible data by at most
// 1/16 (LZO: n + n/16 + 67; LZ4 and zstd less); 64 KiB covers the header and metadata.
// So: 32*w*h + 2*w*h + 64 KiB (about 8.6 MiB for 512 x 512).
int64_t maxPixelMessageBytes(int width, int height);

// Before binding an ipc:// endpoint: if its socket file answers, a live process (another
// farm) holds it, and binding would silently take it over; throws std::runtime_error naming
// the endpoint and what the folder's `farm` file says of its owner. A file nobody answers
// on is left by a dead farm: it is removed (and said). Other transports: nothing to do.
void claimIpcEndpoint(const std::string& endpoint);

// The note an ipc:// farm leaves in its endpoint folder (`farm`: its run and master pid),
// which claimIpcEndpoint quotes to a second farm; removed with this object. Other
// transports: nothing.
class FarmNote {
 public:
  FarmNote(const std::string& endpoint_base, const std::string& text);
  ~FarmNote();
  FarmNote(const FarmNote&) = delete;
  FarmNote& operator=(const FarmNote&) = delete;

 private:
  std::string path_;
};

}  // namespace tessera
