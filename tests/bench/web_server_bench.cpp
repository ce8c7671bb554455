// tessera-web-server-bench: civetweb (the web view's server) against libwebsockets, the two
// WebSocket servers Debian 12 packages, on what the web view does with them: frames of a given
// size pushed to one viewer with at most 2 unacknowledged (the viewer acknowledges each by id,
// as the page does), and a viewer that sends one oversized message. Prints frames per second,
// the median time from a frame's write to its acknowledgement, the server's CPU time per frame
// and how much the server's peak memory grew for a 64 MiB message it must refuse. The viewer
// is a child process (civetweb's client) so that the server's CPU time is its own.
// A benchmark, not a timed test.
#include <libwebsockets.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "tests/bench/web_server_bench.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace tessera::bench;

double cpuMs() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto ms = [](const timeval& t) { return (double)t.tv_sec * 1e3 + (double)t.tv_usec / 1e3; };
  return ms(u.ru_utime) + ms(u.ru_stime);
}

// This process's peak resident memory in MiB since the last resetPeak().
double peakMiB() {
  std::ifstream in("/proc/self/status");
  for (std::string l; std::getline(in, l);)
    if (l.rfind("VmHWM:", 0) == 0) return std::stod(l.substr(6)) / 1024;
  return 0;
}
void resetPeak() { std::ofstream("/proc/self/clear_refs") << "5"; }

// The libwebsockets server: one service thread; frames go out when the connection is writable
// and fewer than 2 are unacknowledged; messages are received 4 KiB at a time, so an oversized
// one is refused after its first 4 KiB.
class LwsServer final : public BenchServer {
 public:
  LwsServer(int port, const Job& job) : BenchServer(job), frame_(LWS_PRE + job.frame_bytes, 7) {
    protocols_[0] = {"tessera", &LwsServer::callback, 0, kMaxMessage, 0, this, job.frame_bytes};
    protocols_[1] = {nullptr, nullptr, 0, 0, 0, nullptr, 0};
    lws_set_log_level(LLL_ERR, nullptr);
    lws_context_creation_info info{};
    info.port = port;
    info.iface = "127.0.0.1";
    info.protocols = protocols_;
    info.user = this;
    ctx_ = lws_create_context(&info);
    if (!ctx_) throw std::runtime_error("libwebsockets: cannot listen on port " + std::to_string(port));
    thread_ = std::thread([this] {
      while (!stop_) lws_service(ctx_, 0);
    });
  }
  ~LwsServer() override {
    stop_ = true;
    lws_cancel_service(ctx_);
    thread_.join();
    lws_context_destroy(ctx_);
  }

 private:
  static int callback(lws* wsi, lws_callback_reasons reason, void*, void* in, size_t len) {
    const lws_protocols* p = lws_get_protocol(wsi);
    auto* self = p ? static_cast<LwsServer*>(p->user) : nullptr;
    if (!self) return 0;
    switch (reason) {
      case LWS_CALLBACK_ESTABLISHED:
        self->connected();
        lws_callback_on_writable(wsi);
        break;
      case LWS_CALLBACK_SERVER_WRITEABLE:
        if (auto id = self->nextToSend()) {
          std::memcpy(self->frame_.data() + LWS_PRE, &*id, sizeof *id);
          if (lws_write(wsi, self->frame_.data() + LWS_PRE, self->job_.frame_bytes, LWS_WRITE_BINARY) < 0) return -1;
          lws_callback_on_writable(wsi);
        }
        break;
      case LWS_CALLBACK_RECEIVE:
        self->message_bytes_ += len;
        if (self->message_bytes_ > kMaxMessage) return self->refuse(), -1;
        if (lws_is_final_fragment(wsi)) {
          self->acked(std::string(static_cast<const char*>(in), len));
          self->message_bytes_ = 0;
          lws_callback_on_writable(wsi);
        }
        break;
      default:
        break;
    }
    return 0;
  }

  lws_protocols protocols_[2]{};
  lws_context* ctx_ = nullptr;
  std::vector<unsigned char> frame_;
  size_t message_bytes_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The viewer (a child process): acknowledges every frame until it has `frames`, or sends one
// message of `send_bytes`; exits 0 when done.
int viewer(int port, const Job& job) {
  struct State {
    int got = 0;
    int want;
  } st{0, job.frames};
  char err[256] = "";
  mg_connection* conn = nullptr;
  for (int i = 0; i < 200 && !conn; ++i, std::this_thread::sleep_for(std::chrono::milliseconds(20)))
    conn = mg_connect_websocket_client(
        "127.0.0.1", port, 0, err, sizeof err, "/ws", nullptr,
        [](mg_connection* c, int bits, char* data, size_t size, void* user) -> int {
          auto& s = *static_cast<State*>(user);
          if ((bits & 0x0f) != MG_WEBSOCKET_OPCODE_BINARY || size < 8) return 1;
          uint64_t id;
          std::memcpy(&id, data, 8);
          const std::string ack = std::to_string(id);
          mg_websocket_client_write(c, MG_WEBSOCKET_OPCODE_TEXT, ack.data(), ack.size());
          ++s.got;
          return 1;
        },
        nullptr, &st);
  if (!conn) return 2;
  // civetweb's client leaves Nagle's algorithm on, so an acknowledgement would wait for the
  // server's delayed ACK; browsers set TCP_NODELAY. This process's one TCP socket is the client's.
  for (int fd = 3; fd < 256; ++fd) {
    int type = 0;
    socklen_t len = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) == 0 && type == SOCK_STREAM) {
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    }
  }
  if (job.send_bytes) {
    const std::string big(job.send_bytes, 'x');
    mg_websocket_client_write(conn, MG_WEBSOCKET_OPCODE_TEXT, big.data(), big.size());
    std::this_thread::sleep_for(std::chrono::seconds(1));
  } else {
    for (auto end = Clock::now() + std::chrono::seconds(120); st.got < st.want && Clock::now() < end;)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  mg_close_connection(conn);
  return st.got >= st.want || job.send_bytes ? 0 : 3;
}

struct Row {
  std::string server, job;
  double fps = 0, ack_ms = 0, cpu_ms_per_frame = 0, peak_growth_mib = 0;
  bool closed = false;
};

Row run(const std::string& name, const Job& job, int port) {
  const pid_t child = fork();
  if (child == 0) _exit(viewer(port, job));
  resetPeak();
  const double peak0 = peakMiB(), cpu0 = cpuMs();
  const auto t0 = Clock::now();
  Row r{name, job.name};
  {
    std::unique_ptr<BenchServer> server;
    if (name == "civetweb") server = makeCivetwebServer(port, job);
    else server = std::make_unique<LwsServer>(port, job);
    int status = 0;
    waitpid(child, &status, 0);
    r.closed = server->refused();
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    r.fps = job.frames ? server->acks() / s : 0;
    r.ack_ms = server->medianAckMs();
    r.cpu_ms_per_frame = job.frames ? (cpuMs() - cpu0) / std::max<double>(1, server->acks()) : 0;
    if (WEXITSTATUS(status) != 0) throw std::runtime_error(name + ": the viewer failed on " + job.name);
  }
  r.peak_growth_mib = peakMiB() - peak0;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tessera-web-server-bench: civetweb against libwebsockets on the web view's traffic"};
  int port = 18090;
  app.add_option("--port", port, "loopback port")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  // A moving frame at 1024² (~10 KB), a lossless one (~216 KB), and a 64 MiB message.
  const std::vector<Job> jobs{{"3000 frames of 10 KB", 10000, 3000, 0},
                              {"300 frames of 216 KB", 216000, 300, 0},
                              {"one 64 MiB message", 1000, 0, 64 << 20}};
  std::printf("| server | traffic | frames/s | write to ack, median ms | server CPU ms per frame | "
              "server peak memory growth MiB | refused |\n|---|---|---:|---:|---:|---:|---|\n");
  for (const Job& job : jobs)
    for (const std::string name : {"civetweb", "libwebsockets"}) {
      const Row r = run(name, job, port++);
      std::printf("| %s | %s | %.0f | %.2f | %.3f | %.1f | %s |\n", r.server.c_str(), r.job.c_str(), r.fps, r.ack_ms,
                  r.cpu_ms_per_frame, r.peak_growth_mib, r.closed ? "yes" : "no");
      std::fflush(stdout);
    }
  return 0;
}
