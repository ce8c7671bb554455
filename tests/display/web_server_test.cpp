// The web view's server alone (no farm, no browser): where it listens, what it refuses to
// start on, and what it serves to a plain HTTP request; and the header of its frames.
#include "display/web_server.h"

#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

#include "display/web_frame.h"

namespace tessera::display {
namespace {

// One HTTP/1.0 GET on loopback; the whole response.
std::string get(int port, const std::string& path) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons((uint16_t)port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval limit{5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  std::string out;
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
    const std::string req = "GET " + path + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
    if (send(fd, req.data(), req.size(), MSG_NOSIGNAL) == (ssize_t)req.size()) {
      char buf[4096];
      for (ssize_t n; (n = recv(fd, buf, sizeof buf, 0)) > 0;) out.append(buf, (size_t)n);
    }
  }
  close(fd);
  return out;
}

std::string whyNot(const std::string& address) {
  try {
    WebServer s(address, "token");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(WebServer, PortZeroListensOnAFreePortAndTheUrlCarriesTheToken) {
  WebServer s("127.0.0.1:0", "tok3n");
  ASSERT_GT(s.port(), 0);
  EXPECT_EQ(s.url(), "http://127.0.0.1:" + std::to_string(s.port()) + "/#tok3n");
  const std::string page = get(s.port(), "/");
  EXPECT_EQ(page.rfind("HTTP/1.", 0), 0u) << page;
  EXPECT_NE(page.find(" 200 "), std::string::npos) << page.substr(0, 200);
  EXPECT_NE(page.find("viewer.js"), std::string::npos) << "the page names its script";
  EXPECT_NE(get(s.port(), "/viewer.js").find("WebSocket"), std::string::npos);
  EXPECT_NE(get(s.port(), "/etc/passwd").find(" 404 "), std::string::npos);
  EXPECT_EQ(s.counters().bad_requests, 1u);
  // All addresses (a container's published port): loopback reaches it too.
  WebServer any("0.0.0.0:0", "tok3n");
  EXPECT_NE(get(any.port(), "/").find(" 200 "), std::string::npos);
}

TEST(WebServer, AnAddressInUseOrNotAPortIsRefusedByName) {
  WebServer first("127.0.0.1:0", "token");
  const std::string taken = "127.0.0.1:" + std::to_string(first.port());
  EXPECT_NE(whyNot(taken).find("--web " + taken + ": cannot listen there"), std::string::npos) << whyNot(taken);
  EXPECT_NE(whyNot("127.0.0.1:http").find("the port must be a number"), std::string::npos);
  EXPECT_NE(whyNot("127.0.0.1:70000").find("the port must be a number"), std::string::npos);
  EXPECT_NE(get(first.port(), "/").find(" 200 "), std::string::npos) << "the first server still serves";
}

TEST(WebServer, BytesThatAreNotARequestAreCountedAndTheServerGoesOn) {
  WebServer s("127.0.0.1:0", "token");
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons((uint16_t)s.port());
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  std::string junk(4096, '\0');
  for (size_t i = 0; i < junk.size(); ++i) junk[i] = (char)(i * 7919 % 251);  // no request line, no CRLF CRLF
  send(fd, junk.data(), junk.size(), MSG_NOSIGNAL);
  timeval limit{5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  char buf[256];
  while (recv(fd, buf, sizeof buf, 0) > 0) {
  }  // until the server closes it
  close(fd);
  EXPECT_NE(get(s.port(), "/").find(" 200 "), std::string::npos) << "the server still serves";
  EXPECT_EQ(s.counters().bad_requests, 1u) << "the garbage, counted once";
}

nlohmann::json headerOf(const WebFrame& f) {
  const uint32_t n = f.message[0] | f.message[1] << 8 | f.message[2] << 16 | (uint32_t)f.message[3] << 24;
  return nlohmann::json::parse(f.message.begin() + 4, f.message.begin() + 4 + n);
}

TEST(WebFrame, AReducedFrameNamesTheFullFrameThePageShowsItAt) {
  Image8 frame(40, 30);  // a reduced frame: one opaque pixel at (5, 7)
  uint8_t* p = frame.at(5, 7);
  p[0] = 200, p[1] = 100, p[2] = 50, p[3] = 255;
  Shown moving{12, "status", true, 80, 60};
  const nlohmann::json h = headerOf(encodeWebFrame(frame, moving, {0, 0, 0}, 90));
  EXPECT_EQ(h["kind"], "jpeg");
  EXPECT_EQ(h["moving"], true);
  EXPECT_EQ(h["x"], 5);
  EXPECT_EQ(h["y"], 7);
  EXPECT_EQ(h["w"], 1);
  EXPECT_EQ(h["h"], 1);
  EXPECT_EQ(h["fw"], 40);
  EXPECT_EQ(h["fh"], 30);
  EXPECT_EQ(h["full"], nlohmann::json::array({80, 60}));
  // Before any full-quality frame the display knows no size to name: the page uses fw, fh.
  const nlohmann::json first = headerOf(encodeWebFrame(frame, Shown{0, "", true}, {0, 0, 0}, 90));
  EXPECT_FALSE(first.contains("full"));
}

}  // namespace
}  // namespace tessera::display
