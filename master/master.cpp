#include "master/master.h"

#include <chrono>
#include <map>
#include <thread>

#include "master/balance.h"
#include "master/interaction.h"
#include "master/tiling.h"
#include "common/net/log.h"
#include "common/net/transport.h"
#include "master/metrics.h"

namespace tessera::master {
namespace {

using Clock = std::chrono::steady_clock;
using proto::Role;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

const char* roleName(Role r) {
  switch (r) {
    case Role::Renderer: return "renderer";
    case Role::Compositor: return "compositor";
    case Role::Display: return "display";
  }
  return "?";
}

struct Member {
  Role role;
  uint32_t rank = 0, pid = 0;
  std::string identity;     // ROUTER routing id
  std::string endpoint;     // compositors: where renderers send pieces
  Clock::time_point last_seen;
  bool alive = true;
};

class Master {
 public:
  Master(const MasterOptions& opt, zmq::context_t& ctx)
      : opt_(opt), pub_(makeSocket(ctx, zmq::socket_type::pub)), ctl_(makeSocket(ctx, zmq::socket_type::router)),
        base_camera_(opt.scene.camera), quality_(opt.scene.quality), metrics_(opt.metrics_path) {
    pub_.bind(opt_.endpoints.bind(opt_.endpoints.masterPub()));
    ctl_.bind(opt_.endpoints.bind(opt_.endpoints.masterControl()));
    total_frames_ = opt_.frames < 0 ? opt_.scene.orbit.frames : opt_.frames;
    spdlog::info("master listening pub={} control={} renderers={} compositors={} frames={} window={}",
                 opt_.endpoints.masterPub(), opt_.endpoints.masterControl(), opt_.renderers, opt_.compositors,
                 total_frames_ == 0 ? std::string("interactive") : std::to_string(total_frames_), opt_.window);
    if (sortFirst() && opt_.scene.antialiasing.method == "fft")
      spdlog::warn("antialiasing fft is a post filter of the whole image, applied by tessera-render; the farm "
                   "renders this scene without it (use msaa or ssaa for identical farm frames)");
    // Sort-first (geometry) scenes need no volume here: renderers own the mesh.
    if (!sortFirst()) volume_ = std::make_shared<Volume>(loadVolume(opt_.scene));
  }

  int run(const std::atomic<bool>* stop) {
    if (!gatherMembers(stop)) return 1;
    assignBricks();
    auto last_probe = Clock::now();
    while (!(stop && *stop)) {
      issueFrames();
      if (finished()) break;
      pollControl(50);
      if (msSince(last_probe) > 250) {  // the probe lets late joiners (spares) join
        sendBytes(pub_, proto::encode(proto::Heartbeat{Role::Display, 0}, kMasterRank));
        checkHeartbeats();
        last_probe = Clock::now();
      }
      metrics_.flushOlderThan(Clock::now() - std::chrono::milliseconds(500));
    }
    // Stats travel apart from FrameDone: give the last frames' reports a moment to land.
    for (auto t = Clock::now(); metrics_.pending() > 0 && msSince(t) < 1000;) pollControl(20);
    metrics_.flushAll();
    shutdown(stop && *stop ? "stopped" : "all frames done");
    return 0;
  }

 private:
  // ---- membership -------------------------------------------------------------------
  bool gatherMembers(const std::atomic<bool>* stop) {
    auto start = Clock::now(), last_probe = Clock::now() - std::chrono::seconds(1);
    while (!(stop && *stop)) {
      if (count(Role::Renderer) >= opt_.renderers && count(Role::Compositor) >= opt_.compositors &&
          count(Role::Display) >= 1)
        return true;
      if (msSince(last_probe) > 100) {
        // Stages say Hello only after this probe reaches them, so their subscription is live.
        sendBytes(pub_, proto::encode(proto::Heartbeat{Role::Display, 0}, kMasterRank));
        last_probe = Clock::now();
      }
      if (msSince(start) > opt_.start_timeout_s * 1000) {
        spdlog::error("stages missing after {:.0f} s: renderers {}/{} compositors {}/{} display {}/1",
                      opt_.start_timeout_s, count(Role::Renderer), opt_.renderers, count(Role::Compositor),
                      opt_.compositors, count(Role::Display));
        return false;
      }
      pollControl(20);
    }
    return false;
  }

  int count(Role r) const {
    int n = 0;
    for (const auto& [key, m] : members_) n += m.role == r && m.alive;
    return n;
  }

  void onHello(const std::string& identity, const proto::Hello& h) {
    uint32_t rank = 0;
    while (members_.count({h.role, rank})) ++rank;
    Member m{h.role, rank, h.pid, identity, "", Clock::now(), true};
    if (h.role == Role::Compositor) m.endpoint = opt_.endpoints.compositorOn(rank, h.endpoint);
    members_[{h.role, rank}] = m;
    sendTo(identity, proto::encode(proto::Welcome{h.role, rank}, kMasterRank));
    spdlog::info("{} {} joined pid={}{}", roleName(h.role), rank, h.pid,
                 m.endpoint.empty() ? "" : " endpoint=" + m.endpoint);
    if (started_) membershipChanged();
  }

  void checkHeartbeats() {
    for (auto& [key, m] : members_) {
      if (!m.alive || msSince(m.last_seen) < opt_.heartbeat_timeout_s * 1000) continue;
      m.alive = false;
      spdlog::warn("{} {} (pid {}) lost: no heartbeat for {:.1f} s; reassigning its work", roleName(m.role), m.rank,
                   m.pid, msSince(m.last_seen) / 1000);
      membershipChanged();
    }
  }

  // A stage came or went: new assignment, and frames in flight are issued again under a
  // new epoch (stages drop work of older epochs), so no frame waits forever for a dead stage.
  void membershipChanged() {
    ++epoch_;
    assignBricks();
    if (renderer_ranks_.empty() || compositors_.empty()) {
      spdlog::warn("no {} left: waiting for one to join", renderer_ranks_.empty() ? "renderer" : "compositor");
      return;  // frames in flight are issued again when one joins (its Hello bumps the epoch)
    }
    for (auto& [frame, f] : inflight_) publish(frame, f.camera);
  }

  // ---- work assignment ---------------------------------------------------------------
  void assignBricks() {
    renderer_ranks_.clear();
    for (const auto& [key, m] : members_)
      if (m.role == Role::Renderer && m.alive) renderer_ranks_.push_back(m.rank);
    compositors_.clear();
    for (const auto& [key, m] : members_)
      if (m.role == Role::Compositor && m.alive) compositors_.push_back(&m);
    int n = std::max<int>(1, (int)renderer_ranks_.size());
    if (!sortFirst()) tree_ = splitBricks(*volume_, n, &opt_.scene.tf);
    started_ = true;
  }

  bool sortFirst() const { return opt_.scene.mesh.has_value(); }

  // Sort-first: tiles for this frame (balanced from the last fully reported frame's
  // per-tile costs, or static equal tiles) dealt to renderers; renderer i's tiles are
  // routed by compositor i mod M, so each renderer sends one framebuffer.
  void assignTiles(proto::FrameParams& p) {
    const int r = (int)renderer_ranks_.size(), m = (int)compositors_.size();
    auto tiles = opt_.balance ? balancedTiles(width(), height(), r * opt_.tiles_per_renderer, cost_)
                              : equalTiles(width(), height(), r * opt_.tiles_per_renderer);
    std::map<uint32_t, Rect> bounds;  // compositor -> bounds of its tiles
    for (size_t i = 0; i < tiles.size(); ++i) {
      int renderer = (int)(i % r);
      const Member* c = compositors_[renderer % m];
      p.tiles.push_back({renderer_ranks_[renderer], c->rank, tiles[i]});
      bounds[c->rank] = unite(bounds[c->rank], tiles[i]);
    }
    for (const Member* c : compositors_)
      if (bounds.count(c->rank)) p.regions.push_back({c->rank, bounds[c->rank], c->endpoint});
  }

  // A renderer's per-tile times, in FrameParams::tiles order; a frame's costs replace the
  // model once every renderer has reported.
  void tileCosts(const proto::StageStats& s) {
    auto it = inflight_tiles_.find(s.frame);
    if (it == inflight_tiles_.end()) return;
    auto& [reports, grid, tiles] = it->second;
    size_t k = 0;
    for (const auto& t : tiles)
      if (t.renderer == s.rank && k < s.tile_ms.size()) grid.add(t.tile, s.tile_ms[k++]);
    if (++reports >= (int)renderer_ranks_.size()) {
      cost_ = grid;
      inflight_tiles_.erase(inflight_tiles_.begin(), std::next(it));
    }
  }

  std::vector<Rect> regions() const {
    int m = (int)compositors_.size();
    if (opt_.balance) return balancedBands(width(), height(), m, last_active_);
    return balancedBands(width(), height(), m, {});
  }

  int width() const { return opt_.scene.width; }
  int height() const { return opt_.scene.height; }

  Camera cameraFor(uint64_t frame) const {
    if (total_frames_ == 0) return base_camera_;
    return opt_.scene.orbit.at(base_camera_, (int)(frame % std::max(1, opt_.scene.orbit.frames)));
  }

  void issueFrames() {
    while ((int)inflight_.size() < opt_.window && !renderer_ranks_.empty() && !compositors_.empty()) {
      if (total_frames_ > 0 && next_frame_ >= (uint64_t)total_frames_) return;
      Camera cam = cameraFor(next_frame_);
      // Interactive: a frame whose inputs did not change is not rendered again.
      if (total_frames_ == 0 && next_frame_ > 0 && cam == last_camera_ && quality_ == last_quality_) return;
      publish(next_frame_, cam);
      last_camera_ = cam;
      last_quality_ = quality_;
      ++next_frame_;
    }
  }

  void publish(uint64_t frame, const Camera& cam) {
    proto::FrameParams p;
    p.frame = frame;
    p.epoch = epoch_;
    p.camera = cam;
    p.quality = quality_;
    p.width = width();
    p.height = height();
    p.codec = opt_.codec;
    p.format = opt_.format;
    if (sortFirst()) {
      assignTiles(p);
      inflight_tiles_[frame] = {0, CostGrid(width(), height()), p.tiles};
    } else {
      for (size_t i = 0; i < tree_.bricks.size(); ++i) p.bricks.push_back({renderer_ranks_[i], tree_.bricks[i]});
      p.order = tree_.visibilityOrder(*volume_, cam);
      auto bands = regions();
      for (size_t i = 0; i < bands.size(); ++i)
        p.regions.push_back({compositors_[i]->rank, bands[i], compositors_[i]->endpoint});
    }
    p.display_endpoint = opt_.endpoints.display();
    inflight_[frame] = {Clock::now(), cam};
    metrics_.issued(frame, epoch_, (int)renderer_ranks_.size(), (int)p.regions.size());
    sendBytes(pub_, proto::encode(p, kMasterRank));
  }

  bool finished() const {
    return total_frames_ > 0 && next_frame_ >= (uint64_t)total_frames_ && inflight_.empty();
  }

  // ---- control messages ---------------------------------------------------------------
  void pollControl(int timeout_ms) {
    zmq::pollitem_t items[] = {{ctl_.handle(), 0, ZMQ_POLLIN, 0}};
    pollFor(items, 1, std::chrono::milliseconds(timeout_ms));
    for (int budget = 0; (items[0].revents & ZMQ_POLLIN) && budget < 1000; ++budget) {
      zmq::message_t id, body;
      if (!ctl_.recv(id, zmq::recv_flags::dontwait)) break;
      if (!id.more()) {
        drops_.drop(~0u, "control message without routing id");
        continue;
      }
      (void)ctl_.recv(body, zmq::recv_flags::none);
      while (body.more()) {  // a peer sent extra frames: keep only the first
        zmq::message_t extra;
        (void)ctl_.recv(extra, zmq::recv_flags::none);
      }
      handle(id.to_string(), body);
    }
  }

  void handle(const std::string& identity, const zmq::message_t& body) {
    auto header = proto::decodeHeader(view(body));
    if (!header) return drops_.drop(~0u, header.error());
    switch (header->type) {
      case proto::Type::Hello: {
        auto h = proto::decodeHello(view(body));
        if (!h) return drops_.drop(header->sender, h.error());
        return onHello(identity, *h);
      }
      case proto::Type::Heartbeat: {
        auto h = proto::decodeHeartbeat(view(body));
        if (!h) return drops_.drop(header->sender, h.error());
        if (auto it = members_.find({h->role, h->rank}); it != members_.end())  // own socket: no identity match
          it->second.last_seen = Clock::now();
        return;
      }
      case proto::Type::Stats: {
        auto s = proto::decodeStageStats(view(body));
        if (!s) return drops_.drop(header->sender, s.error());
        touch(identity);
        if (s->role == Role::Renderer && s->frame + 1 >= latest_active_frame_) {
          if (s->frame + 1 > latest_active_frame_) last_active_.clear();
          latest_active_frame_ = s->frame + 1;
          last_active_.push_back(s->active);
        }
        if (s->role == Role::Renderer && sortFirst()) tileCosts(*s);
        return metrics_.stats(*s);
      }
      case proto::Type::FrameDone: {
        auto d = proto::decodeFrameDone(view(body));
        if (!d) return drops_.drop(header->sender, d.error());
        touch(identity);
        auto it = inflight_.find(d->frame);
        if (it == inflight_.end()) return drops_.drop(header->sender, "FrameDone for a frame not in flight");
        metrics_.done(*d, msSince(it->second.issued), drops_.total());
        inflight_.erase(it);
        return;
      }
      case proto::Type::Input: {
        auto in = proto::decodeInput(view(body));
        if (!in) return drops_.drop(header->sender, in.error());
        return onInput(*in);
      }
      default:
        return drops_.drop(header->sender, std::string("unexpected ") + proto::typeName(header->type));
    }
  }

  void touch(const std::string& identity) {
    for (auto& [key, m] : members_)
      if (m.identity == identity) m.last_seen = Clock::now();
  }

  void onInput(const proto::Input& in) {
    try {
      base_camera_ = applyInput(base_camera_, in);
      if (!in.quality.empty()) quality_ = namedQuality(in.quality);
    } catch (const std::invalid_argument& e) {
      drops_.drop(~0u, e.what());
    }
  }

  void sendTo(const std::string& identity, std::vector<std::byte>&& bytes) {
    ctl_.send(zmq::buffer(identity), zmq::send_flags::sndmore);
    sendBytes(ctl_, std::move(bytes));
  }

  void shutdown(const std::string& reason) {
    spdlog::info("master shutting down: {} frames={} dropped={}", reason, metrics_.framesDone(), drops_.total());
    // PUB is fire-and-forget: say it a few times so every subscriber hears it.
    for (int i = 0; i < 5; ++i) {
      sendBytes(pub_, proto::encode(proto::Shutdown{reason}, kMasterRank));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  static constexpr uint32_t kMasterRank = 0xFFFF;

  struct InFlight {
    Clock::time_point issued;
    Camera camera;
  };

  const MasterOptions& opt_;
  zmq::socket_t pub_, ctl_;
  std::shared_ptr<Volume> volume_;
  std::map<std::pair<Role, uint32_t>, Member> members_;
  std::vector<uint32_t> renderer_ranks_;
  std::vector<const Member*> compositors_;
  BrickTree tree_;
  CostGrid cost_{1, 1};
  struct TileReports {
    int reports = 0;
    CostGrid grid{1, 1};
    std::vector<proto::TileAssignment> tiles;
  };
  std::map<uint64_t, TileReports> inflight_tiles_;
  bool started_ = false;
  uint32_t epoch_ = 0;
  uint64_t next_frame_ = 0;
  int total_frames_ = 0;
  std::map<uint64_t, InFlight> inflight_;
  Camera base_camera_, last_camera_;
  Quality quality_, last_quality_;
  std::vector<Rect> last_active_;
  uint64_t latest_active_frame_ = 0;
  DropCounter drops_;
  Metrics metrics_;
};

}  // namespace

int run(const MasterOptions& opt, zmq::context_t& ctx, const std::atomic<bool>* stop) {
  Master m(opt, ctx);
  return m.run(stop);
}

}  // namespace tessera::master
