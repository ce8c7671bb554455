// CURVE authentication and encryption for TCP between hosts (libzmq's CurveZMQ). A farm has
// one keypair, kept in a folder that every process of the farm reads (compose mounts it);
// holding its secret key is what makes a process a member. Sockets that bind are CURVE
// servers with the farm secret key; sockets that connect are CURVE clients that present the
// farm keypair and expect the farm public key from the server. A ZAP handler on the context
// admits only clients that proved the farm key; everyone else is refused and counted.
// CurveAuth is thread-safe once constructed; one per zmq::context_t.
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include <zmq.hpp>

namespace tessera {

struct FarmKeys {
  std::string public_z85, secret_z85;  // 40 Z85 characters each
};

FarmKeys generateFarmKeys();
// <dir>/farm.key (the secret, mode 0600) and <dir>/farm.pub. farm.key appears atomically, so
// processes that start together agree on one key. Returns false (writing nothing) if the
// folder already has a farm.key. Throws naming the file when it cannot write.
bool writeFarmKeys(const std::string& dir, const FarmKeys& keys);
// The keys from farm.key (the public key derives from it; farm.pub, if present, must match).
// Throws std::runtime_error naming the file and what is wrong with it.
FarmKeys readFarmKeys(const std::string& dir);
// The folder's keys, created on first use (by the master, or tessera-keys; concurrent starts agree).
FarmKeys loadOrCreateFarmKeys(const std::string& dir);
// The folder's keys once they are there: a stage on a host without them must not make a key
// of its own (no peer would admit it), so it waits up to `wait_s` for the master to create
// them, saying so, then throws naming the folder.
FarmKeys awaitFarmKeys(const std::string& dir, double wait_s);

// Why a CURVE client's handshakes fail, read from a ZeroMQ socket monitor. A server that holds
// another farm key cannot open the client's first message and closes the connection before
// any key check (so before it could log a refusal), and a server without CURVE speaks another
// mechanism: either way the client only sees its handshakes fail, and says why.
class HandshakeWatch {
 public:
  HandshakeWatch(zmq::context_t& ctx, zmq::socket_t& client);
  ~HandshakeWatch();
  HandshakeWatch(const HandshakeWatch&) = delete;
  HandshakeWatch& operator=(const HandshakeWatch&) = delete;
  // Reads the events so far (non-blocking): "" unless at least `failures` handshakes failed
  // since the last that succeeded, or one failed for a mechanism mismatch; then what the
  // user should check.
  std::string failing(int failures);

 private:
  zmq::socket_t& client_;
  zmq::socket_t pair_;
  int failed_ = 0;
  bool mechanism_ = false;  // a failure said the peer speaks another mechanism
};

// True when traffic to or from this endpoint may leave the machine: tcp to any host that is
// not a loopback address or "localhost" (ipc:// and inproc:// never leave it).
bool endpointLeavesHost(const std::string& endpoint);

class CurveAuth {
 public:
  CurveAuth(zmq::context_t& ctx, FarmKeys keys);
  ~CurveAuth();
  CurveAuth(const CurveAuth&) = delete;
  CurveAuth& operator=(const CurveAuth&) = delete;

  void makeServer(zmq::socket_t& s) const;  // call before bind
  void makeClient(zmq::socket_t& s) const;  // call before connect
  uint64_t refused() const { return refused_; }  // handshakes refused for a wrong key

 private:
  void serveRequests(zmq::socket_t& s, const std::array<uint8_t, 32>& farm, zmq::pollitem_t* items);
  zmq::context_t& ctx_;
  FarmKeys keys_;
  std::atomic<bool> quit_{false};
  std::atomic<uint64_t> refused_{0};
  std::thread zap_;
};

// Process-wide CURVE, decided once by a process's main: on when TESSERA_CURVE=on, or when it
// is unset/auto and `base_endpoint` or TESSERA_BIND_HOST leaves the host; off with
// TESSERA_CURVE=off (logged as a warning if traffic leaves the host). Keys come from the
// folder TESSERA_KEYS (default ./keys): created there by a process that `makes_keys` (the
// master), awaited by the others (awaitFarmKeys). Returns whether it is on.
bool setupCurve(zmq::context_t& ctx, const std::string& base_endpoint, bool makes_keys = false);
// Bind / connect a socket, as a CURVE server / client when CURVE is on for this process.
void bindTo(zmq::socket_t& s, const std::string& endpoint);
void connectTo(zmq::socket_t& s, const std::string& endpoint);
// Removes the ipc:// socket files this process bound (those not taken over since): a stage
// that ends leaves nothing in its endpoint folder.
void removeBoundIpcFiles();
// Handshakes this process refused for a wrong key (0 when CURVE is off).
uint64_t curveRefused();
// Turns process-wide CURVE off again (tests that run several farms in one process).
void resetCurve();

}  // namespace tessera
