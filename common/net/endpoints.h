// Where the farm's sockets live, derived from one base address so that replicas need no
// per-process configuration. ipc://DIR puts sockets in DIR; tcp://HOST:PORT uses PORT..PORT+2
// for the master and display and PORT+10+rank for compositors (renderers' binary-swap
// sockets take a port the system picks: swapBind); inproc://NAME runs a farm
// inside one process (tests). Loopback by default: nothing listens publicly unless asked.
#pragma once
#include <cstdint>
#include <string>

namespace tessera {

struct Endpoints {
  std::string base;
  std::string masterPub() const;      // master binds PUB (FrameParams, Shutdown)
  std::string masterControl() const;  // master binds ROUTER (Hello, Heartbeat, Stats, FrameDone, Input)
  std::string display() const;        // display binds PULL (Strips)
  std::string compositor(uint32_t rank) const;       // address compositors advertise
  // The same on a named host (tcp only; containers advertise their own hostname).
  std::string compositorOn(uint32_t rank, const std::string& host) const;
  std::string compositorBind(uint32_t rank) const;   // address a compositor binds
  // Where a renderer binds the socket that takes its binary-swap partners' pieces, before it
  // has a rank: tcp on TESSERA_BIND_HOST (default the base host) at a port the system picks
  // (so farms sharing a node never collide), ipc/inproc named by `unique`.
  std::string swapBind(const std::string& unique) const;
  // What peers connect to once that socket is bound at `bound` (ZeroMQ's last endpoint):
  // tcp on `host`, or ("" ) the bound address, or when bound on every interface the address
  // on the route to the master; others as bound.
  std::string swapAdvertised(const std::string& bound, const std::string& host) const;
  // Bind forms: tcp binds on TESSERA_BIND_HOST (default: the base host) so containers can
  // bind 0.0.0.0 while peers connect by service name.
  std::string bind(const std::string& connect_form) const;
  // tcp: the address of this machine's interface that routes to the master (what a peer on
  // another host can reach us at, without naming hosts: Swarm tasks, DHCP nodes).
  std::string localAddressTowardMaster() const;
};

// Validates the base (ipc://, tcp://host:port, inproc://); throws std::invalid_argument.
Endpoints makeEndpoints(const std::string& base);
// TESSERA_ENDPOINTS, or ipc://<tmp>/tessera-<uid> when unset.
std::string defaultEndpointBase();
// What a stage advertises to its peers: "hostname" = this machine's name, "ip" = its address
// on the route to the master (tcp only), anything else as given ("" = the base host).
std::string resolveAdvertiseHost(const std::string& advertise, const Endpoints& endpoints);
// The farm this process belongs to: TESSERA_RUN (tessera-up makes one per run), "" if unset.
// Stages say it in their Hello; a master refuses a stage of another run.
std::string farmRun();
// Why a peer's advertised address cannot be connected to ("" when it can): `host` as
// ZeroMQ's tcp takes it (a name or IPv4 address of letters, digits, '.', '-', '_', or an
// IPv6 address in brackets); `endpoint` on the transport of the farm's `base`.
std::string hostProblem(const std::string& host);
std::string peerEndpointProblem(const std::string& endpoint, const std::string& base);
// A tcp bind endpoint as ZeroMQ can bind it: ZeroMQ binds addresses and interface names
// only, so a host name (Slurm's NodeAddr, `tcp://master:5550` on the master's own host) is
// resolved to its IPv4 address here; anything else is returned unchanged. Throws naming the
// endpoint when the name does not resolve.
std::string bindableEndpoint(const std::string& endpoint);
// Whether a tcp endpoint's host (a name or address) is an address of this machine; true also
// for ipc/inproc, for 0.0.0.0 and when it cannot tell (a name that does not resolve here).
// What a stage checks before it tells peers to send to that address.
bool endpointIsHere(const std::string& endpoint);
// A tcp endpoint's host ("tcp://[::1]:5550" -> "::1"): without an IPv6 address's brackets.
std::string tcpHost(const std::string& endpoint);
// The environment variable `name`, or `fallback` when it is unset or empty.
std::string envOr(const char* name, const std::string& fallback);

}  // namespace tessera
