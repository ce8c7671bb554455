// A stage's link to the master: SUB for FrameParams/Shutdown, DEALER for Hello and
// reports, and a heartbeat thread (its own socket) so a long render never looks like a
// dead stage. join() waits for the master's probe (so the subscription is live), says
// Hello and waits for the Welcome that carries this stage's rank.
// Both DEALER sockets carry explicit routing ids: 16 random bytes (first nonzero) plus 'c'
// (control) or 'h' (heartbeat), so the master binds the heartbeat connection to the member
// that said Hello on the control connection (see heartbeatIdentity).
#pragma once
#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "common/net/curve.h"
#include "common/net/endpoints.h"
#include "common/net/log.h"
#include "common/wire/protocol.h"

namespace tessera {

class StageLink {
 public:
  // `scene`: the stage's sceneIdentity, said in its Hello (the master refuses any other).
  StageLink(zmq::context_t& ctx, const Endpoints& ep, proto::Role role, std::string scene, std::string advertise = "");
  ~StageLink();
  StageLink(const StageLink&) = delete;
  StageLink& operator=(const StageLink&) = delete;

  // False if `stop` was raised, the master refused this stage or shut down, or nothing came
  // from the master for timeout_s (its probes, while it prepares, keep the wait going).
  static constexpr double kHelloEveryS = 10;  // Hello is said again this often until the Welcome
  bool join(const std::atomic<bool>* stop, double timeout_s = 120);
  // join() returned false because the master said Shutdown: the run ended before this stage
  // joined (a spare started late), which is no failure of this stage.
  bool runEnded() const { return run_ended_; }
  uint32_t rank() const { return rank_; }
  // The Welcome's volume_range ({0, 0}: the master gave none).
  std::array<double, 2> volumeRange() const { return volume_range_; }
  // What Hello says as this stage's endpoint (before join): a compositor's advertised host, a
  // renderer's swap socket.
  void setAdvertised(std::string endpoint) { advertise_ = std::move(endpoint); }
  zmq::socket_t& sub() { return sub_; }
  // Drains what the master published (non-blocking): FrameParams in order, and whether it
  // said Shutdown. Its membership probes are skipped; malformed messages are dropped and counted.
  struct Published {
    std::vector<proto::FrameParams> params;
    bool shutdown = false;
  };
  Published receive(DropCounter& drops, int max_messages = 256);
  // Published before the Welcome and not read yet: receive() has them though the SUB socket
  // does not poll readable.
  bool pending() const { return !early_.empty(); }
  // The frame size this stage's buffers and message limits were made for (its own scene):
  // FrameParams for a larger frame are passed on, and the mismatch is logged once as an
  // error naming both sizes (a master started with another scene than this stage).
  void expectFrameSize(int width, int height) { max_w_ = width, max_h_ = height; }
  // The master probes every 250 ms: this long without a word means it is gone, and a stage
  // left alone (outside the launcher) exits instead of waiting forever.
  bool masterLost() const;
  static constexpr double kMasterSilenceS = 10.0;
  void report(std::vector<std::byte>&& msg);  // to the master, from the owning thread
  const std::string& identity() const { return identity_; }  // control connection's routing id
  // The heartbeat connection's routing id for a control routing id ("" if not of our form).
  static std::string heartbeatIdentity(const std::string& control_identity);
  // The routing id this stage's data sockets (pieces, strips) must carry: the master names it
  // in the Roster it sends privately to the stages that receive them.
  static std::string dataIdentity(const std::string& control_identity);
  const std::string dataIdentity() const { return dataIdentity(identity_); }
  // Drains the master's private messages on the control connection (non-blocking) and
  // returns the newest Roster among them; anything else is dropped and counted.
  std::optional<proto::Roster> receiveRoster(DropCounter& drops, int max_messages = 64);
  zmq::socket_t& control() { return ctl_; }
  // What the heartbeats say this stage waits for in a frame: a binary swap's partner, the
  // renderer whose piece a compositor lacks, the sender of strips the display lacks (the
  // master's deadline then blames whoever the chain of waits ends at), or nothing.
  void setWaiting(uint64_t frame, uint32_t partner);
  void clearWaiting() { setWaiting(0, proto::kNobody); }

 private:
  // Why this farm's master said Shutdown, or nothing: not a Shutdown, or one of another run (a
  // master that used this endpoint just before ours), which `other` explains.
  std::optional<std::string> ourShutdown(const zmq::message_t& published, std::string* other = nullptr) const;
  // After the master's Shutdown during join, a Welcome it sent just before may still be on its way.
  static constexpr double kWelcomeGraceS = 0.3;
  int max_w_ = 0, max_h_ = 0;  // 0: no expected size
  bool size_logged_ = false;
  zmq::context_t& ctx_;
  Endpoints ep_;
  proto::Role role_;
  std::string scene_;
  std::string advertise_;
  std::string identity_;
  const std::string run_;  // TESSERA_RUN
  bool run_ended_ = false;
  zmq::socket_t sub_, ctl_;
  // Watches sub_'s handshakes from before it connects (a mechanism mismatch is one event,
  // never retried) until the stage has joined.
  std::unique_ptr<HandshakeWatch> handshakes_;
  uint32_t rank_ = 0;
  std::array<double, 2> volume_range_{0, 0};
  std::atomic<bool> quit_{false};
  std::mutex waiting_mutex_;  // the heartbeat thread reads both fields together
  uint64_t waiting_frame_ = 0;
  uint32_t waiting_for_ = proto::kNobody;
  std::chrono::steady_clock::time_point last_heard_ = std::chrono::steady_clock::now();
  std::thread heartbeat_;
  std::deque<zmq::message_t> early_;  // published before the Welcome: receive() reads them first
  static constexpr size_t kEarlyKept = 256;  // the newest: only those just before the Welcome can be for this stage
};

}  // namespace tessera
