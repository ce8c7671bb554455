// Farm keys and the ZAP handler (see curve.h).
#include "common/net/curve.h"

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <chrono>
#include <memory>
#include <mutex>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "common/net/endpoints.h"
#include "common/net/transport.h"

namespace tessera {
namespace {

constexpr size_t kZ85KeyLength = 40;
constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";  // fixed by the ZAP specification (RFC 27)

std::string readKeyFile(const std::filesystem::path& p) {
  std::ifstream in(p);
  if (!in) throw std::runtime_error(p.string() + ": cannot read the farm key (create it with tessera-keys)");
  std::string key;
  in >> key;
  if (key.size() != kZ85KeyLength)
    throw std::runtime_error(p.string() + ": expected a 40-character Z85 key, found " + std::to_string(key.size()) +
                             " characters");
  std::array<uint8_t, 32> raw{};
  if (!zmq_z85_decode(raw.data(), key.c_str())) throw std::runtime_error(p.string() + ": not a Z85 key");
  return key;
}

void writeText(const std::filesystem::path& p, const std::string& text, mode_t mode) {
  {
    std::ofstream out(p, std::ios::trunc);
    if (!out || !(out << text << '\n')) throw std::runtime_error(p.string() + ": cannot write the farm key");
  }
  if (chmod(p.c_str(), mode) != 0) throw std::runtime_error(p.string() + ": cannot set its permissions");
}

std::unique_ptr<CurveAuth> g_curve;  // set once by a process's main (setupCurve)

}  // namespace

FarmKeys generateFarmKeys() {
  char pub[41] = {}, sec[41] = {};
  if (zmq_curve_keypair(pub, sec) != 0)
    throw std::runtime_error("libzmq cannot make CURVE keys (built without CURVE support?)");
  return {pub, sec};
}

bool writeFarmKeys(const std::string& dir, const FarmKeys& keys) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const fs::path key = fs::path(dir) / "farm.key", tmp = fs::path(dir) / (".farm.key." + std::to_string(getpid()));
  writeText(tmp, keys.secret_z85, 0600);
  const bool created = link(tmp.c_str(), key.c_str()) == 0;  // atomic: exactly one writer wins
  const int err = errno;
  fs::remove(tmp);
  if (!created && err != EEXIST) throw std::runtime_error(key.string() + ": cannot create the farm key");
  if (created) {
    // Whole or not at all: the farm's other processes, started at the same time, read it as
    // soon as farm.key exists (an empty farm.pub once stopped a display of a test's farm).
    const fs::path pub = fs::path(dir) / "farm.pub", pub_tmp = fs::path(dir) / (".farm.pub." + std::to_string(getpid()));
    writeText(pub_tmp, keys.public_z85, 0644);
    fs::rename(pub_tmp, pub);
  }
  return created;
}

FarmKeys readFarmKeys(const std::string& dir) {
  namespace fs = std::filesystem;
  FarmKeys k;
  k.secret_z85 = readKeyFile(fs::path(dir) / "farm.key");
  char derived[41] = {};
  if (zmq_curve_public(derived, k.secret_z85.c_str()) != 0)
    throw std::runtime_error(dir + "/farm.key: not a CURVE secret key");
  k.public_z85 = derived;
  if (fs::exists(fs::path(dir) / "farm.pub") && readKeyFile(fs::path(dir) / "farm.pub") != k.public_z85)
    throw std::runtime_error(dir + "/farm.pub does not belong to " + dir + "/farm.key");
  return k;
}

FarmKeys loadOrCreateFarmKeys(const std::string& dir) {
  if (!std::filesystem::exists(std::filesystem::path(dir) / "farm.key") && writeFarmKeys(dir, generateFarmKeys()))
    spdlog::info("created farm keys in {}/ (farm.key is the secret every process of the farm needs)", dir);
  return readFarmKeys(dir);
}

FarmKeys awaitFarmKeys(const std::string& dir, double wait_s) {
  const std::filesystem::path key = std::filesystem::path(dir) / "farm.key";
  const auto start = std::chrono::steady_clock::now();
  for (bool said = false; !std::filesystem::exists(key); said = true) {
    if (!said)
      spdlog::info("no farm key in {}/ yet: waiting up to {:.0f} s for the master to create it (on another host than "
                   "the master's, copy its keys/ folder here and point TESSERA_KEYS at it)", dir, wait_s);
    if (std::chrono::steady_clock::now() - start > std::chrono::duration<double>(wait_s))
      throw std::runtime_error("no farm key in " + key.string() + " after " + std::to_string((int)wait_s) +
                               " s: copy the master's keys/ folder to this host (tessera-keys DIR makes one) and " +
                               "point TESSERA_KEYS at it");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return readFarmKeys(dir);
}

HandshakeWatch::HandshakeWatch(zmq::context_t& ctx, zmq::socket_t& client)
    : client_(client), pair_(ctx, zmq::socket_type::pair) {
  static std::atomic<int> next{0};
  const std::string at = "inproc://tessera-handshake-" + std::to_string(next++);
  const int events = ZMQ_EVENT_HANDSHAKE_SUCCEEDED | ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL |
                     ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL | ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;
  if (zmq_socket_monitor(client_.handle(), at.c_str(), events) != 0) throw zmq::error_t();
  pair_.set(zmq::sockopt::linger, 0);
  pair_.connect(at);
}

HandshakeWatch::~HandshakeWatch() { zmq_socket_monitor(client_.handle(), nullptr, 0); }

std::string HandshakeWatch::failing(int failures) {
  zmq::message_t event, address;
  while (pair_.recv(event, zmq::recv_flags::dontwait)) {
    if (event.more()) (void)pair_.recv(address);
    if (event.size() < 6) continue;
    uint16_t what = 0;
    uint32_t value = 0;
    std::memcpy(&what, event.data(), 2);
    std::memcpy(&value, static_cast<const char*>(event.data()) + 2, 4);
    if (what == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) failed_ = 0, mechanism_ = false;
    else ++failed_, mechanism_ = mechanism_ || (what == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL &&
                                                value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH);
  }
  // A mechanism mismatch is said once: ZeroMQ does not try that connection again.
  if (!mechanism_ && failed_ < failures) return "";
  int mechanism = ZMQ_NULL;
  size_t size = sizeof mechanism;
  zmq_getsockopt(client_.handle(), ZMQ_MECHANISM, &mechanism, &size);
  const bool curve = mechanism == ZMQ_CURVE;
  if (mechanism_)
    return std::string("the master speaks another security mechanism: CURVE is on at one end only (TESSERA_CURVE here ") +
           (curve ? "on" : "off") + "; it is on where endpoints leave the host, or with TESSERA_CURVE=on)";
  // The master closed them: it could not open this stage's first message (another farm key)
  // or it expected another mechanism and said so first (CURVE on there only).
  return std::to_string(failed_) + " handshakes failed: the master closed them; " +
         (curve ? "this stage's farm key is not the master's (give every host a copy of the master's keys/ folder, "
                  "TESSERA_KEYS), or CURVE is off at the master (TESSERA_CURVE)"
                : "CURVE is off here, and the master probably has it on (TESSERA_CURVE=on, or endpoints that leave "
                  "the host)");
}

bool endpointLeavesHost(const std::string& endpoint) {
  if (endpoint.rfind("tcp://", 0) != 0) return false;
  const std::string host = tcpHost(endpoint);
  return !(host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0);
}

CurveAuth::CurveAuth(zmq::context_t& ctx, FarmKeys keys) : ctx_(ctx), keys_(std::move(keys)) {
  // Bind before any CURVE server exists, or its first handshakes would find no handler.
  auto rep = std::make_shared<zmq::socket_t>(ctx_, zmq::socket_type::rep);
  rep->set(zmq::sockopt::linger, 0);
  rep->bind(kZapEndpoint);
  zap_ = std::thread([this, rep] {
    zmq::socket_t s = std::move(*rep);
    std::array<uint8_t, 32> farm{};
    zmq_z85_decode(farm.data(), keys_.public_z85.c_str());
    zmq::pollitem_t items[] = {{s.handle(), 0, ZMQ_POLLIN, 0}};
    try {
      serveRequests(s, farm, items);
    } catch (const zmq::error_t&) {  // the context is terminating: the process is ending
    }
  });
}

void CurveAuth::serveRequests(zmq::socket_t& s, const std::array<uint8_t, 32>& farm, zmq::pollitem_t* items) {
  while (!quit_) {
    pollFor(items, 1, std::chrono::milliseconds(100));
    if (!(items[0].revents & ZMQ_POLLIN)) continue;
    // Request: version, request id, domain, address, identity, mechanism, credentials...
    std::vector<zmq::message_t> frames;
    do {
      frames.emplace_back();
      if (!s.recv(frames.back(), zmq::recv_flags::dontwait)) break;
    } while (frames.back().more() && frames.size() < 16);
    const bool curve = frames.size() >= 7 && frames[5].to_string() == "CURVE";
    const bool member = curve && frames[6].size() == farm.size() &&
                        std::equal(farm.begin(), farm.end(), static_cast<const uint8_t*>(frames[6].data()));
    if (!member) {
      uint64_t n = ++refused_;
      if (n <= 3 || (n & (n - 1)) == 0)
        spdlog::warn("refused peer address={} reason=\"{}\" refused_total={}",
                     frames.size() > 3 ? frames[3].to_string() : "?", curve ? "not the farm key" : "not CURVE", n);
    }
    const std::string id = frames.size() > 1 ? frames[1].to_string() : "";
    s.send(zmq::str_buffer("1.0"), zmq::send_flags::sndmore);
    s.send(zmq::buffer(id), zmq::send_flags::sndmore);
    s.send(zmq::buffer(std::string(member ? "200" : "400")), zmq::send_flags::sndmore);
    s.send(zmq::buffer(std::string(member ? "OK" : "not a member of this farm")), zmq::send_flags::sndmore);
    s.send(zmq::str_buffer(""), zmq::send_flags::sndmore);  // user id
    s.send(zmq::str_buffer(""), zmq::send_flags::none);     // metadata
  }
}

CurveAuth::~CurveAuth() {
  quit_ = true;
  if (zap_.joinable()) zap_.join();
}

void CurveAuth::makeServer(zmq::socket_t& s) const {
  s.set(zmq::sockopt::curve_server, 1);
  s.set(zmq::sockopt::curve_secretkey, keys_.secret_z85);
  s.set(zmq::sockopt::zap_domain, "tessera");
}

void CurveAuth::makeClient(zmq::socket_t& s) const {
  s.set(zmq::sockopt::curve_serverkey, keys_.public_z85);
  s.set(zmq::sockopt::curve_publickey, keys_.public_z85);
  s.set(zmq::sockopt::curve_secretkey, keys_.secret_z85);
}

bool setupCurve(zmq::context_t& ctx, const std::string& base_endpoint, bool makes_keys) {
  const char* mode_env = std::getenv("TESSERA_CURVE");
  const std::string mode = mode_env && *mode_env ? mode_env : "auto";
  if (mode != "auto" && mode != "on" && mode != "off")
    throw std::invalid_argument("TESSERA_CURVE=" + mode + ": expected auto, on or off");
  const char* bind_host = std::getenv("TESSERA_BIND_HOST");
  const bool leaves = endpointLeavesHost(base_endpoint) ||
                      (bind_host && *bind_host && endpointLeavesHost("tcp://" + std::string(bind_host) + ":1"));
  if (mode == "off" || (mode == "auto" && !leaves)) {
    if (leaves) spdlog::warn("TESSERA_CURVE=off: traffic to {} leaves this host unauthenticated and unencrypted", base_endpoint);
    return false;
  }
  const char* keys_env = std::getenv("TESSERA_KEYS");
  const std::string dir = keys_env && *keys_env ? keys_env : "keys";
  g_curve = std::make_unique<CurveAuth>(ctx, makes_keys ? loadOrCreateFarmKeys(dir) : awaitFarmKeys(dir, 120));
  spdlog::info("CURVE on: peers must hold the farm key in {}/", dir);
  return true;
}

// ipc socket files this process bound (path, inode), removed by removeBoundIpcFiles.
std::mutex g_bound_mu;
std::vector<std::pair<std::string, ino_t>> g_bound;

void bindTo(zmq::socket_t& s, const std::string& wanted) {
  const std::string endpoint = bindableEndpoint(wanted);
  claimIpcEndpoint(endpoint);
  if (g_curve && endpoint.rfind("tcp://", 0) == 0) g_curve->makeServer(s);
  try {
    s.bind(endpoint);
  } catch (const zmq::error_t& e) {
    // ZeroMQ's own words name neither the address nor what to change.
    const std::string as = endpoint == wanted ? wanted : wanted + " (" + endpoint + ")";
    std::string hint;
    if (e.num() == EADDRINUSE) hint = ": the port is taken, by another farm or program (TESSERA_ENDPOINTS chooses the ports)";
    else if (e.num() == EADDRNOTAVAIL || e.num() == ENODEV)
      hint = ": not an address of this host (TESSERA_BIND_HOST: this host's address, or 0.0.0.0 for all)";
    throw std::runtime_error("cannot bind " + as + ": " + e.what() + hint);
  }
  struct stat st {};
  if (endpoint.rfind("ipc://", 0) == 0 && stat(endpoint.c_str() + 6, &st) == 0) {
    std::lock_guard lock(g_bound_mu);
    g_bound.emplace_back(endpoint.substr(6), st.st_ino);
  }
}

void removeBoundIpcFiles() {
  std::lock_guard lock(g_bound_mu);
  for (const auto& [path, inode] : g_bound) {
    struct stat st {};
    if (stat(path.c_str(), &st) == 0 && st.st_ino == inode) unlink(path.c_str());  // still ours
  }
  g_bound.clear();
}

void connectTo(zmq::socket_t& s, const std::string& endpoint) {
  if (g_curve && endpoint.rfind("tcp://", 0) == 0) g_curve->makeClient(s);
  s.connect(endpoint);
}

uint64_t curveRefused() { return g_curve ? g_curve->refused() : 0; }

void resetCurve() { g_curve.reset(); }

}  // namespace tessera
