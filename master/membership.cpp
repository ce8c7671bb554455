#include "master/membership.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "common/net/endpoints.h"
#include "common/net/stage_link.h"
#include "master/plan.h"

namespace tessera::master {

using proto::Role;

double Membership::quarantineS(int strikes) {
  if (strikes <= 0) return 0;
  return std::min(60.0, 5.0 * std::pow(2.0, strikes - 1));
}

Member& Membership::join(const std::string& identity, const proto::Hello& h, Clock::time_point now, bool* joined) {
  if (Member* m = byControlIdentity(identity)) {
    if (joined) *joined = false;
    return *m;
  }
  uint32_t rank = 0;
  while (members_.count({h.role, rank})) ++rank;
  Member m;
  m.role = h.role;
  m.rank = rank;
  m.pid = h.pid;
  m.id = (uint32_t)members_.size();
  m.identity = identity;
  m.heartbeat_identity = StageLink::heartbeatIdentity(identity);
  m.last_seen = now;
  if (joined) *joined = true;
  return members_[{h.role, rank}] = m;
}

Member* Membership::byIdentity(const std::string& identity) {
  for (auto& [key, m] : members_)
    if (m.identity == identity || (!m.heartbeat_identity.empty() && m.heartbeat_identity == identity)) return &m;
  return nullptr;
}

Member* Membership::byControlIdentity(const std::string& identity) {
  for (auto& [key, m] : members_)
    if (m.identity == identity) return &m;
  return nullptr;
}

bool Membership::heard(Member& m, Clock::time_point now) {
  m.last_seen = now;
  if (m.alive) return false;
  if (std::chrono::duration<double>(now - m.lost_at).count() < quarantineS(m.strikes)) return false;
  m.alive = true;
  return true;
}

std::vector<Member*> Membership::expire(Clock::time_point now, double timeout_s) {
  std::vector<Member*> lost;
  for (auto& [key, m] : members_) {
    if (!m.alive || std::chrono::duration<double>(now - m.last_seen).count() < timeout_s) continue;
    m.alive = false;
    m.lost_at = now;
    m.waiting_for = proto::kNobody;  // until its next heartbeat
    lost.push_back(&m);
  }
  return lost;
}

void Membership::missedDeadline(Member& m, Clock::time_point now, const Member* named_by) {
  m.alive = false;
  m.lost_at = now;
  m.waiting_for = proto::kNobody;  // until its next heartbeat
  ++m.strikes;
  if (Member* r = named_by ? find(named_by->role, named_by->rank) : nullptr) r->named = m.rank, r->named_at = now;
}

int Membership::count(Role r) const {
  int n = 0;
  for (const auto& [key, m] : members_) n += m.role == r && m.alive;
  return n;
}

std::string Membership::missing(int renderers, int compositors) const {
  const int r = count(Role::Renderer), c = count(Role::Compositor), d = count(Role::Display);
  if (r >= renderers && c >= compositors && d >= 1) return "";
  return fmt::format("renderers {}/{} compositors {}/{} display {}/1", r, renderers, c, compositors, d);
}

std::vector<const Member*> Membership::alive(Role r) const {
  std::vector<const Member*> out;
  for (const auto& [key, m] : members_)  // the map is ordered by (role, rank)
    if (m.role == r && m.alive) out.push_back(&m);
  return out;
}

const Member* Membership::find(Role r, uint32_t rank) const {
  auto it = members_.find({r, rank});
  return it == members_.end() ? nullptr : &it->second;
}

Member* Membership::find(Role r, uint32_t rank) {
  auto it = members_.find({r, rank});
  return it == members_.end() ? nullptr : &it->second;
}

const Member* Membership::display() const {
  auto d = alive(Role::Display);
  return d.empty() ? nullptr : d.front();
}

proto::Roster Membership::roster() const {
  proto::Roster r{epoch_, {}};
  for (proto::Role role : {proto::Role::Renderer, proto::Role::Compositor})
    for (const Member* m : alive(role))
      if (auto id = StageLink::dataIdentity(m->identity); !id.empty()) r.members.push_back({role, m->rank, id});
  return r;
}

std::string describeWaiting(const Membership& members, uint64_t frame, const CreditWindow::Waiting& w,
                            Clock::time_point now, const Member** culprit, const Member** named_by) {
  const auto& renderers = w.renderers;
  std::vector<std::string> parts;
  *culprit = nullptr;
  auto name = [&](proto::Role role, uint32_t rank, const char* what) {
    const Member* m = members.find(role, rank);
    if (!*culprit) *culprit = m;
    return fmt::format("{} {} {} (pid {})", what, proto::roleName(role), rank, m ? m->pid : 0);
  };
  for (uint32_t r : renderers) parts.push_back(name(proto::Role::Renderer, r, "stats from"));
  for (uint32_t c : w.compositors) parts.push_back(name(proto::Role::Compositor, c, "strips from"));
  if (const Member* d = members.display(); w.display && d) parts.push_back(name(proto::Role::Display, d->rank, "FrameDone from"));
  // A compositor or the display that says whose parts of this frame it lacks, from a sender
  // that has reported: they were lost on the way (a failed link). The sender is the one to
  // drop; the display never is while it can name one (its loss ends the farm).
  using std::chrono::seconds;
  if (const Member* c = *culprit; c && c->role != proto::Role::Renderer && c->alive && now - c->last_seen < seconds(1) &&
                                  c->waiting_frame == frame && c->waiting_for != proto::kNobody) {
    const proto::Role from = c->role == proto::Role::Display ? w.display_sources : proto::Role::Renderer;
    const bool shedding = c->named != proto::kNobody && c->named != c->waiting_for && now - c->named_at < seconds(60);
    if (const Member* s = members.find(from, c->waiting_for)) {
      parts.push_back(fmt::format("{} {} awaits {} {}'s {}{}", proto::roleName(c->role), c->rank, proto::roleName(from),
                                  s->rank, c->role == proto::Role::Display ? "strips" : "piece",
                                  shedding ? ", another than the one it lacked last" : ""));
      if (!shedding) *culprit = s;
      if (!shedding && named_by) *named_by = c;
    }
  }
  // Follow the waits of a binary swap: a renderer awaiting a partner's piece is not the culprit.
  std::vector<const Member*> chain;
  for (const Member* m = *culprit; m && m->role == proto::Role::Renderer && m->waiting_frame == frame &&
                                   m->waiting_for != proto::kNobody;) {
    if (std::find(chain.begin(), chain.end(), m) != chain.end()) {  // they await each other: no end to blame
      *culprit = chain.front();
      break;
    }
    chain.push_back(m);
    if (std::find(renderers.begin(), renderers.end(), m->waiting_for) == renderers.end()) break;  // it reported
    const Member* next = members.find(proto::Role::Renderer, m->waiting_for);
    if (!next || !next->alive) break;
    parts.push_back(fmt::format("renderer {} awaits renderer {}'s swap piece", m->rank, next->rank));
    *culprit = m = next;
  }
  return fmt::format("{}", fmt::join(parts, " and "));
}

namespace {
// The line of `text` that starts at `at`, quoted; a long one as 80 characters around column
// `col` (where two texts first differ); "(none)" past the text's end.
std::string lineAt(const std::string& text, size_t at, size_t col) {
  if (at >= text.size()) return "(none)";
  const std::string line = text.substr(at, text.find('\n', at) - at);
  if (line.size() <= 100) return fmt::format("'{}'", line);
  const size_t from = col > 40 ? col - 40 : 0;
  return fmt::format("'{}{}{}'", from > 0 ? "..." : "", line.substr(from, 80), from + 80 < line.size() ? "..." : "");
}
}  // namespace

std::string helloRefusal(const proto::Hello& h, const std::string& run, const std::string& scene,
                         const std::string& endpoint_base) {
  if (h.run != run)
    return fmt::format("this farm is run '{}', the {} (pid {}) is of run '{}'; give every stage of the farm the same "
                       "TESSERA_RUN, or check TESSERA_ENDPOINTS if it is another farm's stage",
                       run, roleName(h.role), h.pid, h.run);
  if (h.scene == scene) return advertiseRefusal(h, endpoint_base);
  size_t line = 1, at = 0, i = 0;  // the first line that differs, where it starts, the first differing byte
  for (; i < std::min(h.scene.size(), scene.size()) && h.scene[i] == scene[i]; ++i)
    if (scene[i] == '\n') ++line, at = i + 1;
  return fmt::format("the {} (pid {}) read another scene than the master: line {} of the scene as they compare it "
                     "(every default filled in; camera, quality, orbit and time playback aside) is {} there and {} "
                     "here; give every stage the same scene file (TESSERA_SCENE)",
                     roleName(h.role), h.pid, line, lineAt(h.scene, at, i - at), lineAt(scene, at, i - at));
}

std::string advertiseRefusal(const proto::Hello& h, const std::string& endpoint_base) {
  if (h.endpoint.empty()) return "";
  std::string why;
  if (h.role == proto::Role::Compositor && endpoint_base.rfind("tcp://", 0) == 0) why = hostProblem(h.endpoint);
  if (h.role == proto::Role::Renderer) why = peerEndpointProblem(h.endpoint, endpoint_base);
  if (why.empty()) return "";
  return fmt::format("the {} (pid {}) advertises an address its peers cannot connect to: {}; check "
                     "TESSERA_ADVERTISE_HOST",
                     roleName(h.role), h.pid, why);
}

Workers aliveWorkers(const Membership& members) {
  Workers w;
  for (const Member* m : members.alive(proto::Role::Renderer)) {
    w.renderers.push_back(m->rank);
    w.renderer_endpoints.push_back(m->endpoint);
  }
  for (const Member* m : members.alive(proto::Role::Compositor)) w.compositors.push_back({m->rank, m->endpoint});
  return w;
}

}  // namespace tessera::master
