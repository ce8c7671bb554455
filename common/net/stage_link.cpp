#include "common/net/stage_link.h"

#include <unistd.h>

#include <chrono>
#include <random>

#include <spdlog/spdlog.h>

#include "common/net/curve.h"

#include "common/net/transport.h"

namespace tessera {

using Clock = std::chrono::steady_clock;

namespace {
constexpr size_t kIdentityBytes = 16;

std::string randomIdentity() {
  std::random_device rd;
  std::string id(kIdentityBytes + 1, '\0');
  for (size_t i = 0; i < kIdentityBytes; ++i) id[i] = static_cast<char>(rd() & 0xFF);
  if (id[0] == '\0') id[0] = 1;  // ZeroMQ reserves routing ids that start with a zero byte
  id[kIdentityBytes] = 'c';
  return id;
}
}  // namespace

std::string StageLink::heartbeatIdentity(const std::string& control_identity) {
  if (control_identity.size() != kIdentityBytes + 1 || control_identity.back() != 'c') return "";
  std::string hb = control_identity;
  hb.back() = 'h';
  return hb;
}

StageLink::StageLink(zmq::context_t& ctx, const Endpoints& ep, proto::Role role, std::string scene,
                     std::string advertise)
    : ctx_(ctx), ep_(ep), role_(role), scene_(std::move(scene)), advertise_(std::move(advertise)),
      identity_(randomIdentity()), run_(farmRun()), sub_(makeSocket(ctx, zmq::socket_type::sub)), ctl_(makeSocket(ctx, zmq::socket_type::dealer)) {
  sub_.set(zmq::sockopt::subscribe, "");
  sub_.set(zmq::sockopt::rcvhwm, 0);  // FrameParams must never be dropped by the queue
  handshakes_ = std::make_unique<HandshakeWatch>(ctx, sub_);
  connectTo(sub_, ep_.masterPub());
  ctl_.set(zmq::sockopt::routing_id, identity_);
  connectTo(ctl_, ep_.masterControl());
}

StageLink::~StageLink() {
  quit_ = true;
  if (heartbeat_.joinable()) heartbeat_.join();
}

std::optional<std::string> StageLink::ourShutdown(const zmq::message_t& published, std::string* other) const {
  auto h = proto::decodeHeader(view(published));
  if (!h || h->type != proto::Type::Shutdown) return std::nullopt;
  auto down = proto::decodeShutdown(view(published));
  if (!down) {
    if (other) *other = "Shutdown: " + down.error();
    return std::nullopt;
  }
  if (down->run != run_) {
    if (other) *other = fmt::format("Shutdown of run '{}' (this farm is run '{}')", down->run, run_);
    return std::nullopt;
  }
  return down->reason;
}

bool StageLink::join(const std::atomic<bool>* stop, double timeout_s) {
  const auto start = Clock::now();
  auto heard = start;  // the master's last probe: a master still reading its volume probes on
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto expired = [&] { return since(heard) > timeout_s; };
  auto shutDown = [&](const std::string& reason) {
    spdlog::info("the master at {} shut down before this {} joined: {}", ep_.masterPub(), proto::roleName(role_), reason);
    run_ended_ = true;
    return false;
  };
  // Never silent: after 2 s, and every 10 s after that, say what this stage waits for.
  double next_notice = 2;
  auto notice = [&](const std::string& what) {
    if (since(start) < next_notice) return;
    spdlog::info("{} waiting {:.0f} s for {} (giving up after {:.0f} s without a word from it; is tessera-master "
                 "running with TESSERA_ENDPOINTS={}?)",
                 proto::roleName(role_), since(start), what, timeout_s, ep_.base);
    next_notice += 10;
  };
  // 1. The master's probe proves our subscription is live before we announce ourselves.
  zmq::pollitem_t sub_item[] = {{sub_.handle(), 0, ZMQ_POLLIN, 0}};
  // A master with another farm key, or without CURVE, fails every handshake at once: said
  // instead of waiting out the timeout (found by review: 120 s of "is tessera-master running?").
  while (true) {
    if ((stop && *stop) || expired()) return false;
    if (const std::string why = handshakes_ ? handshakes_->failing(5) : ""; !why.empty()) {
      spdlog::error("{} cannot join the master at {}: {}", proto::roleName(role_), ep_.masterPub(), why);
      return false;
    }
    notice("the master at " + ep_.masterPub());
    pollFor(sub_item, 1, std::chrono::milliseconds(100));
    if (sub_item[0].revents & ZMQ_POLLIN) {
      zmq::message_t m;
      (void)sub_.recv(m);
      std::string other;
      auto down = ourShutdown(m, &other);
      if (!other.empty()) continue;  // not from this farm's master
      if (down) return shutDown(*down);
      heard = Clock::now();
      handshakes_.reset();  // the subscription is live: its handshake succeeded
      break;
    }
  }
  // 2. Hello until Welcome. A master reading a volume file for its range answers once it
  // has it, however long that takes, and probes meanwhile: only its silence ends the wait.
  // Hello is said again now and then (a master restarted meanwhile never got the first);
  // the master answers a repeated one with the same Welcome.
  // A Shutdown read now may have been said just after our Welcome, which travels on the other
  // connection: the stage waits a moment for it, and if it comes, joins and reads the Shutdown
  // in receive() like any stage (a spare welcomed as the run ends exits as the others do).
  const double hello_every = std::min(kHelloEveryS, timeout_s / 4);
  auto hello_at = Clock::now() - std::chrono::hours(1);
  std::optional<std::string> down;
  auto down_at = Clock::now();
  zmq::pollitem_t items[] = {{ctl_.handle(), 0, ZMQ_POLLIN, 0}, {sub_.handle(), 0, ZMQ_POLLIN, 0}};
  while (true) {
    if ((stop && *stop) || expired()) return false;
    if (down && since(down_at) > kWelcomeGraceS) return shutDown(*down);
    if (!down && since(hello_at) > hello_every) {
      sendBytes(ctl_, proto::encode(proto::Hello{role_, (uint32_t)getpid(), advertise_, run_, scene_}, 0));
      hello_at = Clock::now();
    }
    notice("the master at " + ep_.masterControl() + " to answer its Hello");
    pollFor(items, 2, std::chrono::milliseconds(100));
    for (int i = 0; i < 64 && (items[1].revents & ZMQ_POLLIN); ++i) {
      zmq::message_t m;
      if (!sub_.recv(m, zmq::recv_flags::dontwait)) break;
      std::string other;
      auto ours = ourShutdown(m, &other);
      if (!other.empty()) continue;  // not from this farm's master
      heard = Clock::now();
      if (ours && !down) down = ours, down_at = heard;
      // Anything else published before the Welcome is kept for receive(), in order.
      if (auto h = proto::decodeHeader(view(m)); h && h->type == proto::Type::Probe) continue;
      if (early_.size() == kEarlyKept) early_.pop_front();
      early_.push_back(std::move(m));
    }
    if (!(items[0].revents & ZMQ_POLLIN)) continue;
    zmq::message_t m;
    (void)ctl_.recv(m);
    if (auto refused = proto::decodeShutdown(view(m))) {  // the master will not have this stage
      spdlog::error("the master at {} refused this {}: {}", ep_.masterControl(), proto::roleName(role_),
                    refused->reason);
      return false;
    }
    auto w = proto::decodeWelcome(view(m));
    if (!w || w->role != role_) {
      spdlog::warn("ignoring unexpected control message while joining: {}", w ? "wrong role" : w.error());
      continue;
    }
    if (down) spdlog::info("welcomed as the master shut down: {}", *down);
    rank_ = w->rank;
    volume_range_ = w->volume_range;
    last_heard_ = Clock::now();
    break;
  }
  heartbeat_ = std::thread([this] {
    zmq::socket_t hb = makeSocket(ctx_, zmq::socket_type::dealer);
    hb.set(zmq::sockopt::routing_id, heartbeatIdentity(identity_));
    connectTo(hb, ep_.masterControl());
    while (!quit_) {
      proto::Heartbeat h{role_, rank_};
      {
        std::lock_guard lock(waiting_mutex_);
        h.waiting_frame = waiting_frame_, h.waiting_for = waiting_for_;
      }
      sendBytes(hb, proto::encode(h, rank_), false, true);
      for (int i = 0; i < 5 && !quit_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  return true;
}

void StageLink::setWaiting(uint64_t frame, uint32_t partner) {
  std::lock_guard lock(waiting_mutex_);
  waiting_frame_ = frame, waiting_for_ = partner;
}

StageLink::Published StageLink::receive(DropCounter& drops, int max_messages) {
  Published out;
  for (int i = 0; i < max_messages; ++i) {
    zmq::message_t m;
    if (!early_.empty()) {
      m = std::move(early_.front());
      early_.pop_front();
    } else if (!sub_.recv(m, zmq::recv_flags::dontwait)) {
      break;
    }
    auto h = proto::decodeHeader(view(m));
    if (!h) {
      drops.drop(~0u, h.error());
      continue;
    }
    if (h->type == proto::Type::Shutdown) {
      std::string other;
      if (ourShutdown(m, &other)) out.shutdown = true;
      else drops.drop(h->sender, other);  // not our master's word: it proves nothing alive
      if (other.empty()) last_heard_ = Clock::now();
      continue;
    }
    last_heard_ = Clock::now();
    if (h->type == proto::Type::Probe) continue;
    auto p = h->type == proto::Type::FrameParams
                 ? proto::decodeFrameParams(view(m))
                 : Result<proto::FrameParams>::fail(std::string("unexpected ") + proto::typeName(h->type) + " on SUB");
    if (!p) {
      drops.drop(h->sender, p.error());
      continue;
    }
    if (max_w_ > 0 && (p->width > max_w_ || p->height > max_h_) && !size_logged_) {
      size_logged_ = true;
      spdlog::error("frame {} is {}x{}, larger than the {}x{} this {} was started for: its pixel messages may be "
                    "refused or dropped. Start every stage of the farm with the same scene (TESSERA_SCENE)",
                    p->frame, p->width, p->height, max_w_, max_h_, proto::roleName(role_));
    }
    out.params.push_back(std::move(*p));
  }
  return out;
}

std::string StageLink::dataIdentity(const std::string& control_identity) {
  std::string data = heartbeatIdentity(control_identity);
  if (!data.empty()) data.back() = 'd';
  return data;
}

std::optional<proto::Roster> StageLink::receiveRoster(DropCounter& drops, int max_messages) {
  std::optional<proto::Roster> newest;
  for (int i = 0; i < max_messages; ++i) {
    zmq::message_t m;
    if (!ctl_.recv(m, zmq::recv_flags::dontwait)) break;
    // The answer to a Hello said again while the master was busy (see join): nothing new.
    if (auto w = proto::decodeWelcome(view(m)); w && w->role == role_ && w->rank == rank_) continue;
    auto r = proto::decodeRoster(view(m));
    if (!r) {
      drops.drop(~0u, "control: " + r.error());
      continue;
    }
    if (!newest || r->epoch >= newest->epoch) newest = std::move(*r);
  }
  return newest;
}

bool StageLink::masterLost() const {
  if (std::chrono::duration<double>(Clock::now() - last_heard_).count() < kMasterSilenceS) return false;
  spdlog::error("master lost: nothing from {} for {:.0f} s", ep_.masterPub(), kMasterSilenceS);
  return true;
}

void StageLink::report(std::vector<std::byte>&& msg) { sendBytes(ctl_, std::move(msg), false, true); }

}  // namespace tessera
