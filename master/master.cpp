#include "master/master.h"

#include <unistd.h>

#include <chrono>
#include <memory>
#include <thread>

#include <fmt/format.h>

#include "common/net/curve.h"
#include "common/net/log.h"
#include "common/net/transport.h"
#include "master/interaction.h"
#include "master/membership.h"
#include "master/metrics.h"
#include "master/plan.h"
#include "master/preparation.h"
#include "master/step_stand_ins.h"

namespace tessera::master {
namespace {

// Largest legitimate control message: a Stats with a time per sort-first tile (1024 renderers
// x 64 tiles x 8 bytes = 512 KiB); ZeroMQ refuses larger ones before reading them.
constexpr int64_t kMaxControlMessage = 1 << 20;
using proto::Role;

// The thin loop: the PUB and ROUTER sockets wired to membership, credit window, plan and metrics.
class Master {
 public:
  Master(const MasterOptions& opt, zmq::context_t& ctx)
      : opt_(opt), pub_(makeSocket(ctx, zmq::socket_type::pub)), ctl_(makeSocket(ctx, zmq::socket_type::router, kMaxControlMessage)),
        window_(opt.in_flight, opt.deadline), total_frames_(opt.frames < 0 ? opt.scene.orbit.frames : opt.frames),
        refinement_(opt.scene), metrics_(opt.metrics_path, total_frames_) {
    // No receive bound: with makeSocket's 64, libzmq lost a third of 300 messages of a peer sending
    // faster than it was read, uncounted (Stats too). Drained every loop (<= 50 ms); FarmFuzz bounds it.
    ctl_.set(zmq::sockopt::rcvhwm, 0);
    bindTo(pub_, opt_.endpoints.bind(opt_.endpoints.masterPub()));
    bindTo(ctl_, opt_.endpoints.bind(opt_.endpoints.masterControl()));
    note_ = std::make_unique<FarmNote>(opt_.endpoints.base, fmt::format("run '{}', tessera-master pid {}", opt_.run, getpid()));
    spdlog::info("master listening pub={} control={} renderers={} compositors={} frames={} in_flight={}{}",
                 opt_.endpoints.masterPub(), opt_.endpoints.masterControl(), opt_.renderers, opt_.compositors,
                 total_frames_ == 0 ? std::string("interactive") : std::to_string(total_frames_), opt_.in_flight,
                 opt_.binary_swap && !opt_.scene.mesh ? " compositing=binary-swap" : "");
    if (total_frames_ == 0) spdlog::info(kSteeringNotice);
    preparation_ = std::make_unique<Preparation>(opt_);  // last: a throw above waits for no reading
  }

  int run(const std::atomic<bool>* stop) {
    try {
      prepared_ = preparation_->await(stop, [this] { probe(), pollControl(0); });
    } catch (const ReadingFailed& e) {  // a bad volume file: the waiting stages hear why now, not after 120 s
      try {
        shutdown(std::string("the volume could not be read: ") + e.what());
      } catch (const std::exception&) {  // the reading's error is the one to report
      }
      throw;
    }
    if (!prepared_) {
      shutdown("stopped while reading the volume");
      return 1;  // as when stopped while gathering the stages
    }
    plan_ = prepared_->plan.get();
    refinement_.setSceneWindow(colorWindow(prepared_->scene));
    for (const auto& [identity, hello] : held_.live()) onHello(identity, hello);
    if (!gatherMembers(stop)) return 1;
    plan_->reassign(workers());
    started_ = true;
    auto last_tick = Clock::now();
    while (!(stop && *stop) && !display_lost_) {
      issueFrames();
      if (finished()) break;
      pollControl(refinement_.interacting(Clock::now()) ? 10 : 50);  // the still frame soon after the drag
      if (msSince(last_tick) > 250) {
        probe();  // lets late joiners (spares) join
        checkHeartbeats();
        watchOldestFrame();
        last_tick = Clock::now();
      }
      metrics_.flushOlderThan(Clock::now() - std::chrono::milliseconds(500));
    }
    // Stats travel apart from FrameDone: give the last frames' reports a moment to land.
    for (auto t = Clock::now(); metrics_.pending() > 0 && msSince(t) < 1000;) pollControl(20);
    metrics_.flushAll();
    shutdown(display_lost_ ? "display lost" : stop && *stop ? "stopped" : "all frames done");
    // Interactive runs end when the display goes; a fixed run without it is a failure.
    return display_lost_ && total_frames_ != 0 ? 1 : 0;
  }

 private:
  // ---- membership -------------------------------------------------------------------
  // Never silent: after 2 s, and every 10 s, it says whom it waits for and where.
  bool gatherMembers(const std::atomic<bool>* stop) {
    auto start = Clock::now(), last_probe = start - std::chrono::seconds(1), last_note = start - std::chrono::seconds(8);
    while (!(stop && *stop)) {
      const std::string missing = members_.missing(opt_.renderers, opt_.compositors);
      if (missing.empty()) return true;
      if (msSince(last_probe) > 100) {
        probe();  // stages say Hello once this reaches them: their subscription is live
        last_probe = Clock::now();
      }
      if (msSince(last_note) > 10000) {
        spdlog::info("waiting for stages at {}: {} (gives up after {:.0f} s)", opt_.endpoints.masterControl(), missing,
                     opt_.start_timeout_s);
        last_note = Clock::now();
      }
      if (msSince(start) > opt_.start_timeout_s * 1000) {
        spdlog::error("stages missing after {:.0f} s: {}", opt_.start_timeout_s, missing);
        return false;
      }
      pollControl(20);
    }
    return false;
  }

  void probe() { sendBytes(pub_, proto::encode(proto::Probe{}, kMasterRank)); }

  void onHello(const std::string& identity, const proto::Hello& h) {
    // A stage of another farm, or of another scene: no rank, no work, and it is told why.
    if (const std::string why = helloRefusal(h, opt_.run, scene_, opt_.endpoints.base); !why.empty()) {
      refuse(why);
      return sendTo(identity, proto::encode(proto::Shutdown{why, opt_.run}, kMasterRank));
    }
    if (!prepared_) {  // still reading the volume: answered once it is read (run)
      if (!held_.hold(identity, h)) drops_.drop(~0u, "while reading the volume: Hellos from too many connections");
      return;
    }
    bool joined = false;
    Member& m = members_.join(identity, h, Clock::now(), &joined);
    // Where peers reach it: a compositor says its host, a renderer its bound swap socket.
    if (joined) m.endpoint = h.role == Role::Compositor ? opt_.endpoints.compositorOn(m.rank, h.endpoint) : h.endpoint;
    sendTo(identity, proto::encode(proto::Welcome{m.role, m.rank, prepared_->volume_range}, kMasterRank));
    if (!joined) return;
    spdlog::info("{} {} joined pid={}{}", roleName(h.role), m.rank, h.pid,
                 m.endpoint.empty() ? "" : " endpoint=" + m.endpoint);
    membersCameOrWent();
  }

  void membersCameOrWent() {
    if (started_) return membershipChanged();
    members_.bumpEpoch();  // every roster has its own epoch: a stage tells an early piece from a stranger's
    sendRoster();
  }

  void checkHeartbeats() {
    auto lost = members_.expire(Clock::now(), opt_.heartbeat_timeout_s);
    for (const Member* m : lost)
      spdlog::warn("{} {} (pid {}) lost: no heartbeat for {:.1f} s; reassigning its work", roleName(m->role),
                   m->rank, m->pid, msSince(m->last_seen) / 1000);
    if (!lost.empty()) afterLoss();
  }

  // Frames go to one display; nobody else holds its half-routed frames, so its loss ends the run.
  void afterLoss() {
    if (members_.count(Role::Display) == 0) {
      display_lost_ = true;
      spdlog::error("the display is lost: frames cannot be completed without it; stopping ({})",
                    total_frames_ == 0 ? "interactive run ends" : "run incomplete");
      return;
    }
    membershipChanged();
  }

  // A frame waiting long gets a warning naming who it waits for; past its deadline, the first
  // stage that has not delivered for it is lost (its heartbeat may be fine: a stage can be
  // alive and useless), and its work goes to the others.
  void watchOldestFrame() {
    auto oldest = window_.oldest(Clock::now());
    if (!oldest || oldest->second < window_.stallMs()) return;
    // Whom it waits for, e.g. "stats from renderer 1 (pid 1234)"; `culprit`: who to drop.
    const Member *culprit = nullptr, *named_by = nullptr;  // named_by: a receiver naming it
    const auto w = window_.waiting(oldest->first);
    const std::string who = describeWaiting(members_, oldest->first, w, Clock::now(), &culprit, &named_by);
    if (oldest->second >= window_.deadlineMs() && culprit && culprit->alive) {  // dead ones: already handled
      spdlog::warn("frame={} missed its deadline of {:.0f} ms waiting for {}: {} {} (pid {}) lost; reassigning its work",
                   oldest->first, window_.deadlineMs(), who, roleName(culprit->role), culprit->rank, culprit->pid);
      members_.missedDeadline(*members_.find(culprit->role, culprit->rank), Clock::now(), named_by);
      return afterLoss();
    }
    if (msSince(last_stall_warning_) < 2000) return;
    last_stall_warning_ = Clock::now();
    spdlog::warn("frame={} waited_ms={:.0f} deadline_ms={:.0f} epoch={}: frame {} waits for {}", oldest->first,
                 oldest->second, window_.deadlineMs(), members_.epoch(), oldest->first, who);
  }

  Workers workers() const { return aliveWorkers(members_); }

  // A stage came or went: new assignment, and frames in flight are issued again under a
  // new epoch (stages drop work of older epochs), so no frame waits forever for a dead stage.
  void membershipChanged() {
    members_.bumpEpoch();
    sendRoster();  // before the FrameParams of the new epoch, so it is there before their pieces
    metrics_.reassigned();
    Workers w = workers();
    plan_->reassign(w);
    if (!plan_->canRun(w)) {
      spdlog::warn("no {} left: waiting for one to join", w.renderers.empty() ? "renderer" : "compositor");
      return;  // frames in flight are issued again when one joins (its Hello bumps the epoch)
    }
    std::vector<std::pair<uint64_t, FrameSpec>> again;
    for (const auto& [frame, f] : window_.frames()) again.emplace_back(frame, f.spec);
    for (const auto& [frame, spec] : again) publish(frame, spec, w);
    metrics_.reissued(again.size());
  }

  // Who may send pieces (also swap pieces) and strips, to their receivers, privately (never on PUB).
  void sendRoster() {
    const auto roster = members_.roster();
    for (Role role : {Role::Renderer, Role::Compositor, Role::Display})
      for (const Member* m : members_.alive(role)) sendTo(m->identity, proto::encode(roster, kMasterRank));
  }

  // ---- frames ---------------------------------------------------------------------------

  void issueFrames() {
    Workers w = workers();
    while (plan_->canRun(w)) {
      if (total_frames_ > 0) {
        if (!window_.hasRoom() || next_frame_ >= (uint64_t)total_frames_) return;
        publish(next_frame_, orbitFrame(prepared_->scene, next_frame_), w);
        ++next_frame_;
        continue;
      }
      // Interactive: the newest view, or nothing when it would show nothing new.
      if (auto cw = refinement_.settledWindow(Clock::now())) spdlog::info("{}", windowNote(prepared_->scene, *cw));
      auto spec = refinement_.next(Clock::now());
      if (!spec) return;
      if (spec->interactive) spec->after_cancel = cancelStale();
      if (!window_.hasRoom(spec->interactive ? kInteractiveInFlight : window_.inFlight())) return;
      publish(next_frame_, *spec, w);
      refinement_.issued(*spec);
      ++next_frame_;
    }
  }

  // Once the camera moves, full frames in flight show a view that is gone: cancel them (they
  // leave the credit window now; stages skip or drop their work) rather than show them.
  bool cancelStale() {
    bool stale = false;
    for (const auto& [frame, f] : window_.frames()) stale = stale || !f.spec.interactive;
    if (!stale) return false;
    for (const auto& [frame, f] : window_.frames()) metrics_.cancelled(frame);
    window_.cancelBelow(first_wanted_ = next_frame_);
    return true;
  }

  void publish(uint64_t frame, const FrameSpec& spec, const Workers& w) {
    proto::FrameParams p;
    p.frame = frame;
    p.epoch = members_.epoch();
    stand_ins_.learn(metrics_.takeMixedSteps());
    setView(p, stand_ins_.sent(spec));  // the renderers get the stand-in; the metrics keep the step asked
    p.codec = opt_.codec;
    // Projections' values travel exact: rgba16f rounds by up to 1/2048, > 1/255 on steep maps.
    p.format = isProjection(opt_.scene.blend) ? proto::PixelFormat::RGBA32F : opt_.format;
    p.first_wanted = first_wanted_;
    plan_->fill(p, w);
    p.display_endpoint = opt_.endpoints.display();
    std::set<uint32_t> renderers = proto::renderersWithWork(p), compositors;
    for (const auto& r : p.regions) compositors.insert(r.compositor);
    window_.issue(frame, p.epoch, spec, renderers, compositors, Clock::now());
    metrics_.issued(frame, p.epoch, (int)w.renderers.size(), (int)p.regions.size(), spec);
    sendBytes(pub_, proto::encode(p, kMasterRank));
  }
  bool finished() const { return total_frames_ > 0 && next_frame_ >= (uint64_t)total_frames_ && window_.empty(); }

  // ---- control messages ---------------------------------------------------------------
  void pollControl(int timeout_ms) {
    zmq::pollitem_t items[] = {{ctl_.handle(), 0, ZMQ_POLLIN, 0}};
    pollFor(items, 1, std::chrono::milliseconds(timeout_ms));
    for (int budget = 0; (items[0].revents & ZMQ_POLLIN) && budget < 1000; ++budget) {
      auto m = receiveRouted(ctl_);  // a multi-part message keeps its first part
      if (!m) break;
      if (!m->has_body) drops_.drop(~0u, "control message without routing id");
      else handle(m->identity, m->body);
    }
  }

  void handle(const std::string& identity, const zmq::message_t& body) {
    auto header = proto::decodeHeader(view(body));
    Member* from = members_.byIdentity(identity);
    const uint32_t key = from ? from->id : ~0u;  // drops are logged per connection, not per claimed rank
    if (!header) return drops_.drop(key, header.error());
    if (header->type == proto::Type::Hello) {
      auto h = proto::decodeHello(view(body));
      if (!h) return drops_.drop(key, h.error());
      return onHello(identity, *h);
    }
    // Everything else only from a connection that joined as a member.
    if (!from) return refuse(std::string("unknown peer sent ") + proto::typeName(header->type));
    if (members_.heard(*from, Clock::now())) {
      spdlog::info("{} {} (pid {}) heard from again: re-admitted", roleName(from->role), from->rank, from->pid);
      membersCameOrWent();
    }
    const bool control = from->identity == identity;
    switch (header->type) {
      case proto::Type::Heartbeat: {
        auto h = proto::decodeHeartbeat(view(body));
        if (!h) return drops_.drop(key, h.error());
        if (h->role != from->role || h->rank != from->rank) return drops_.drop(key, "Heartbeat for another member");
        from->waiting_frame = h->waiting_frame, from->waiting_for = h->waiting_for;
        return;
      }
      case proto::Type::Stats: {
        auto s = proto::decodeStageStats(view(body));
        if (!s) return drops_.drop(key, s.error());
        if (!control || s->role != from->role || s->rank != from->rank)
          return drops_.drop(key, "Stats claiming another member");
        window_.stats(s->role, s->rank, s->frame, s->epoch);
        plan_->stats(*s, workers());
        return metrics_.stats(*s);
      }
      case proto::Type::FrameDone: {
        auto d = proto::decodeFrameDone(view(body));
        if (!d) return drops_.drop(key, d.error());
        if (!control || from != members_.display()) return drops_.drop(key, "FrameDone not from the display");
        return onFrameDone(*d, key);
      }
      case proto::Type::Input: {
        auto in = proto::decodeInput(view(body));
        if (!in) return drops_.drop(key, in.error());
        if (!control || from->role != Role::Display) return drops_.drop(key, "Input not from a display");
        // A fixed-length run renders the orbit it was asked for: input would change every later frame.
        if (total_frames_ != 0) return drops_.drop(key, "Input refused: not an interactive run (frames > 0)");
        return onInput(*in, key);
      }
      default:
        return drops_.drop(key, std::string("unexpected ") + proto::typeName(header->type));
    }
  }

  void refuse(const std::string& why) {
    metrics_.refused();
    drops_.drop(~0u, why);
  }

  void onFrameDone(const proto::FrameDone& d, uint32_t key) {
    auto done = window_.done(d.frame, Clock::now());
    if (!done && d.frame < first_wanted_) return;  // cancelled, shown before the display heard it
    if (!done) return drops_.drop(key, "FrameDone for a frame not in flight");
    refinement_.interactiveDone(done->first, done->second);
    metrics_.done(d, done->second, drops_.total());
  }

  void onInput(const proto::Input& in, uint32_t key) {
    try {
      refinement_.input(in, Clock::now());
    } catch (const std::invalid_argument& e) {
      drops_.drop(key, e.what());
    }
  }

  void sendTo(const std::string& identity, std::vector<std::byte>&& bytes) {
    ctl_.send(zmq::buffer(identity), zmq::send_flags::sndmore);
    sendBytes(ctl_, std::move(bytes));
  }

  void shutdown(const std::string& reason) {
    spdlog::info("master shutting down: {} frames={} dropped={} refused_peers={}; {}", reason, metrics_.framesDone(),
                 drops_.total(), metrics_.refusedPeers(), metrics_.runSummary());
    // PUB is fire-and-forget: say it a few times so every subscriber hears it.
    for (int i = 0; i < 5; ++i) {
      sendBytes(pub_, proto::encode(proto::Shutdown{reason, opt_.run}, kMasterRank));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  static constexpr uint32_t kMasterRank = 0xFFFF;
  // Interactive frames in flight at most: each one more adds a frame time to the latency.
  static constexpr int kInteractiveInFlight = 1;

  const MasterOptions& opt_;
  const std::string scene_ = sceneIdentity(opt_.scene);  // what every stage must have read
  zmq::socket_t pub_, ctl_;
  Membership members_;
  CreditWindow window_;
  std::unique_ptr<Preparation> preparation_;  // started once the sockets are bound
  HeldHellos held_;  // while the volume is read
  std::unique_ptr<Prepared> prepared_;
  Plan* plan_ = nullptr;  // prepared_'s
  bool started_ = false, display_lost_ = false;
  Clock::time_point last_stall_warning_;
  uint64_t next_frame_ = 0, first_wanted_ = 0;
  const int total_frames_;  // 0: interactive
  Refinement refinement_;
  DropCounter drops_;
  Metrics metrics_;
  StepStandIns stand_ins_;
  std::unique_ptr<FarmNote> note_;
};

}  // namespace

int run(const MasterOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  return Master(opt, ctx).run(stop);
}

}  // namespace tessera::master
