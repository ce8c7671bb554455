#include "common/net/endpoints.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include <spdlog/spdlog.h>

namespace tessera {
namespace {

bool startsWith(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }

struct TcpBase {
  std::string host;
  int port;
};

TcpBase parseTcp(const std::string& base) {
  auto rest = base.substr(6);
  auto colon = rest.rfind(':');
  if (colon == std::string::npos) throw std::invalid_argument("endpoint base '" + base + "': expected tcp://HOST:PORT");
  int port = 0;
  try {
    port = std::stoi(rest.substr(colon + 1));
  } catch (const std::exception&) {
    port = -1;
  }
  if (port <= 0 || port > 65535 - 100) throw std::invalid_argument("endpoint base '" + base + "': bad port");
  return {rest.substr(0, colon), port};
}

// 127/8 (Debian names its host 127.0.1.1) or ::1.
bool isLoopback(const sockaddr* a) {
  if (a->sa_family == AF_INET) return (ntohl(reinterpret_cast<const sockaddr_in*>(a)->sin_addr.s_addr) >> 24) == 127;
  return a->sa_family == AF_INET6 && IN6_IS_ADDR_LOOPBACK(&reinterpret_cast<const sockaddr_in6*>(a)->sin6_addr);
}

bool sameAddress(const sockaddr* a, const sockaddr* b) {
  if (a->sa_family != b->sa_family) return false;
  if (a->sa_family == AF_INET)
    return reinterpret_cast<const sockaddr_in*>(a)->sin_addr.s_addr == reinterpret_cast<const sockaddr_in*>(b)->sin_addr.s_addr;
  const auto& x = reinterpret_cast<const sockaddr_in6*>(a)->sin6_addr.s6_addr;
  return a->sa_family == AF_INET6 && std::equal(std::begin(x), std::end(x), reinterpret_cast<const sockaddr_in6*>(b)->sin6_addr.s6_addr);
}

}  // namespace

std::string tcpHost(const std::string& endpoint) {
  std::string host = endpoint.substr(6, endpoint.rfind(':') - 6);
  if (host.size() > 1 && host.front() == '[') host = host.substr(1, host.size() - 2);
  return host;
}

std::string envOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

Endpoints makeEndpoints(const std::string& base) {
  if (startsWith(base, "tcp://")) {
    parseTcp(base);
  } else if (startsWith(base, "ipc://")) {
    std::filesystem::create_directories(base.substr(6));
  } else if (!startsWith(base, "inproc://")) {
    throw std::invalid_argument("endpoint base '" + base + "': expected ipc://DIR, tcp://HOST:PORT or inproc://NAME");
  }
  return Endpoints{base};
}

std::string farmRun() { return envOr("TESSERA_RUN", ""); }

std::string hostProblem(const std::string& host) {
  if (host.empty()) return "no host";
  if (host.size() > 253) return "a host name of " + std::to_string(host.size()) + " characters (at most 253)";
  if (host.front() == '[') {  // IPv6, as ZeroMQ takes it
    in6_addr a{};
    if (host.back() != ']' || inet_pton(AF_INET6, host.substr(1, host.size() - 2).c_str(), &a) != 1)
      return "'" + host + "' is not an IPv6 address in brackets";
    return "";
  }
  // Names and IPv4 addresses; '_' too, as container names have it and resolvers take it.
  for (char c : host)
    if (!(std::isalnum((unsigned char)c) || c == '.' || c == '-' || c == '_'))
      return "'" + host + "' has the character '" + std::string(1, c) + "', which no host name or address has";
  return "";
}

std::string peerEndpointProblem(const std::string& endpoint, const std::string& base) {
  const std::string transport = base.substr(0, base.find("://") + 3);
  if (!startsWith(endpoint, transport)) return "'" + endpoint + "' is not a " + transport + " endpoint, as this farm's are";
  if (transport != "tcp://") return endpoint.size() > transport.size() ? "" : "'" + endpoint + "' names no socket";
  const std::string rest = endpoint.substr(6);
  const size_t colon = rest.rfind(':');
  if (colon == std::string::npos) return "'" + endpoint + "' has no port (tcp://HOST:PORT)";
  const std::string port = rest.substr(colon + 1);
  if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      std::stoi(port) < 1 || std::stoi(port) > 65535)
    return "'" + endpoint + "' has no port from 1 to 65535";
  return hostProblem(rest.substr(0, colon));
}

std::string defaultEndpointBase() {
  return envOr("TESSERA_ENDPOINTS",
               "ipc://" + (std::filesystem::temp_directory_path() / ("tessera-" + std::to_string(getuid()))).string());
}

// host_env: the variable that may name this endpoint's host ("" = always the base host).
static std::string named(const std::string& base, const std::string& name, int port_offset,
                         const std::string& host_env) {
  if (startsWith(base, "tcp://")) {
    auto t = parseTcp(base);
    std::string host = host_env.empty() ? t.host : envOr(host_env.c_str(), t.host);
    return "tcp://" + host + ":" + std::to_string(t.port + port_offset);
  }
  if (startsWith(base, "inproc://")) return base + "-" + name;
  return base + "/" + name;
}

std::string Endpoints::masterPub() const { return named(base, "master-pub", 0, "TESSERA_MASTER_HOST"); }
std::string Endpoints::masterControl() const { return named(base, "master-ctl", 1, "TESSERA_MASTER_HOST"); }
std::string Endpoints::display() const { return named(base, "display", 2, "TESSERA_DISPLAY_HOST"); }
std::string Endpoints::compositor(uint32_t rank) const {
  return named(base, "compositor-" + std::to_string(rank), 10 + (int)rank, "");
}
std::string Endpoints::compositorOn(uint32_t rank, const std::string& host) const {
  if (host.empty() || !startsWith(base, "tcp://")) return compositor(rank);
  return "tcp://" + host + ":" + std::to_string(parseTcp(base).port + 10 + (int)rank);
}

std::string Endpoints::compositorBind(uint32_t rank) const { return bind(compositor(rank)); }

std::string Endpoints::swapBind(const std::string& unique) const {
  if (!startsWith(base, "tcp://")) return named(base, "renderer-" + unique, 0, "");
  return "tcp://" + envOr("TESSERA_BIND_HOST", parseTcp(base).host) + ":*";
}

std::string Endpoints::swapAdvertised(const std::string& bound, const std::string& host) const {
  if (!startsWith(bound, "tcp://")) return bound;
  const size_t colon = bound.rfind(':');
  if (!host.empty()) return "tcp://" + host + bound.substr(colon);
  const std::string bound_host = bound.substr(6, colon - 6);
  // Bound on every interface: the one that routes to the master is the one peers can reach.
  if (bound_host == "0.0.0.0" || bound_host == "[::]") return "tcp://" + localAddressTowardMaster() + bound.substr(colon);
  return bound;
}

std::string resolveAdvertiseHost(const std::string& advertise, const Endpoints& endpoints) {
  if (advertise == "hostname") {
    char name[256] = {};
    gethostname(name, sizeof name - 1);
    return name;
  }
  if (advertise == "ip") return endpoints.localAddressTowardMaster();
  return advertise;
}

std::string Endpoints::bind(const std::string& connect_form) const {
  if (!startsWith(connect_form, "tcp://")) return connect_form;
  auto t = parseTcp(connect_form);
  return "tcp://" + envOr("TESSERA_BIND_HOST", t.host) + ":" + std::to_string(t.port);
}

std::string bindableEndpoint(const std::string& endpoint) {
  if (!startsWith(endpoint, "tcp://")) return endpoint;
  const size_t colon = endpoint.rfind(':');
  const std::string host = endpoint.substr(6, colon - 6);  // brackets kept: an IPv6 address binds as it is
  if (host == "*" || host.empty() || host.front() == '[' || if_nametoindex(host.c_str()) != 0) return endpoint;
  in_addr numeric{};
  if (inet_pton(AF_INET, host.c_str(), &numeric) == 1) return endpoint;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || !found)
    throw std::runtime_error("cannot bind " + endpoint + ": '" + host + "' is neither an address nor an interface, and " +
                             "as a host name it does not resolve here (" + gai_strerror(rc) + "); set TESSERA_BIND_HOST " +
                             "to this host's address or 0.0.0.0");
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(found->ai_addr)->sin_addr, text, sizeof text);
  const bool loopback = isLoopback(found->ai_addr);
  freeaddrinfo(found);
  // /etc/hosts often maps the machine's own name to loopback (Debian: 127.0.1.1): bound
  // there, no other host reaches it.
  if (loopback && host != "localhost")
    spdlog::warn("binding {}: '{}' resolves to {} here, a loopback address no other host can reach; for a farm across "
                 "hosts set TESSERA_BIND_HOST to this host's address or 0.0.0.0", endpoint, host, text);
  return "tcp://" + std::string(text) + endpoint.substr(colon);
}

bool endpointIsHere(const std::string& endpoint) {
  if (!startsWith(endpoint, "tcp://")) return true;
  const std::string host = tcpHost(endpoint);
  if (host == "*" || host == "0.0.0.0" || host == "::") return true;
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || !found) return true;
  ifaddrs* ifs = nullptr;
  if (getifaddrs(&ifs) != 0) return freeaddrinfo(found), true;
  bool here = false;  // loopback, or an interface's address (getifaddrs lists only 127.0.0.1 of 127/8)
  for (addrinfo* a = found; a && !here; a = a->ai_next) {
    here = isLoopback(a->ai_addr);
    for (ifaddrs* i = ifs; i && !here; i = i->ifa_next) here = i->ifa_addr && sameAddress(a->ai_addr, i->ifa_addr);
  }
  freeifaddrs(ifs);
  freeaddrinfo(found);
  return here;
}

std::string Endpoints::localAddressTowardMaster() const {
  if (!startsWith(base, "tcp://")) throw std::invalid_argument("advertise host 'ip' needs tcp endpoints, not " + base);
  const std::string host = envOr("TESSERA_MASTER_HOST", parseTcp(base).host);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.c_str(), "9", &hints, &found) != 0 || !found) {
    throw std::runtime_error("advertise host 'ip': cannot resolve the master's host " + host);
  }
  // Connecting a UDP socket only asks the kernel for a route; nothing is sent.
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local{};
  socklen_t len = sizeof local;
  const bool ok = fd >= 0 && connect(fd, found->ai_addr, found->ai_addrlen) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len) == 0;
  if (fd >= 0) close(fd);
  freeaddrinfo(found);
  char text[INET_ADDRSTRLEN] = {};
  if (!ok || !inet_ntop(AF_INET, &local.sin_addr, text, sizeof text)) {
    throw std::runtime_error("advertise host 'ip': no route to the master's host " + host);
  }
  return text;
}

}  // namespace tessera
