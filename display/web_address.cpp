// Where the web view listens, and its token: the parts of starting it that need no
// libwebsockets. See web_server.h.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <stdexcept>

#include "display/web_server.h"

namespace tessera::display {

std::string webToken() {
  if (const char* t = std::getenv("TESSERA_WEB_TOKEN"); t && *t) return t;
  std::random_device rd;
  std::string token;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", (unsigned)rd());
    token += part;
  }
  return token;
}

WebAddress parseWebAddress(const std::string& given) {
  // PORT or :PORT listens on loopback: nothing is served beyond this host unless asked.
  const size_t colon = given.rfind(':');
  WebAddress a;
  a.host = colon == std::string::npos || colon == 0 ? "127.0.0.1" : given.substr(0, colon);
  const std::string port = colon == std::string::npos ? given : given.substr(colon + 1);
  char* end = nullptr;
  const long number = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end || number < 0 || number > 65535)
    throw std::runtime_error("--web " + given + ": the port must be a number from 0 to 65535");
  a.port = (int)number;
  // Tried here first, as libwebsockets will (SO_REUSEADDR): a port in use gets its reason
  // from the system, and libwebsockets' failure path (which leaks) is not taken.
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons((uint16_t)a.port);
  if (a.port != 0 && inet_pton(AF_INET, a.host.c_str(), &sa.sin_addr) == 1) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    const int failed = bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 ? errno : 0;
    close(fd);
    if (failed)
      throw std::runtime_error("--web " + a.host + ":" + port + ": cannot listen there (" + std::strerror(failed) + ")");
  }
  return a;
}

}  // namespace tessera::display
