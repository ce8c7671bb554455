// Who is in the farm: members join with Hello (role, then the lowest free rank of that
// role), are bound to the ZeroMQ connections they use (control routing id, and the
// heartbeat routing id derived from it), are lost when silent or when they miss a frame's
// deadline, and are re-admitted when heard from again. The epoch (bumped by the master once
// work is under way) tells stages which assignment is current.
// Plain values, no sockets; time is passed in so tests control it.
#pragma once
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/clock.h"
#include "common/wire/protocol.h"
#include "master/credit_window.h"

namespace tessera::master {


using proto::roleName;

struct Member {
  proto::Role role = proto::Role::Renderer;
  uint32_t rank = 0, pid = 0;
  uint32_t id = 0;               // small, stable per member: the key of its drop log
  std::string identity;          // control connection (ROUTER routing id)
  std::string heartbeat_identity;  // heartbeat connection ("" if unknown)
  std::string endpoint;          // compositors: where renderers send pieces
  Clock::time_point last_seen, lost_at;
  bool alive = true;
  int strikes = 0;               // deadlines missed: each one doubles its quarantine
  uint64_t waiting_frame = 0;    // its last heartbeat: whose swap piece (a renderer), piece (a
                                 // compositor) or strips (the display) of which frame it awaits
  uint32_t waiting_for = proto::kNobody;
  // A receiver (compositor, display): the sender a deadline last dropped because it named it.
  uint32_t named = proto::kNobody;
  Clock::time_point named_at;
};

class Membership {
 public:
  // A member that missed `strikes` deadlines is not re-admitted before this has passed
  // since it was lost (a stage that heartbeats but never delivers must not stall every
  // frame); a stage lost only by silence is re-admitted as soon as it is heard again.
  static double quarantineS(int strikes);

  // A Hello from `identity`. A second Hello on a joined connection returns that member
  // unchanged (the Welcome is only repeated). `joined` tells which.
  Member& join(const std::string& identity, const proto::Hello& h, Clock::time_point now, bool* joined = nullptr);

  // The member that owns this connection (control or heartbeat), or nullptr.
  Member* byIdentity(const std::string& identity);
  // The member that said Hello on this control connection, or nullptr.
  Member* byControlIdentity(const std::string& identity);

  // Something came from `m`. True when this re-admitted it (lost -> alive).
  bool heard(Member& m, Clock::time_point now);
  // Marks alive members silent for longer than timeout_s lost; returns them.
  std::vector<Member*> expire(Clock::time_point now, double timeout_s);
  // `m` missed a frame's deadline: lost, with one strike more; `named_by`: the receiver whose
  // heartbeats named it (describeWaiting), which remembers that.
  void missedDeadline(Member& m, Clock::time_point now, const Member* named_by = nullptr);

  int count(proto::Role r) const;  // alive members of role r
  // "" once the farm has `renderers`, `compositors` and a display alive, else who is there
  // out of whom: "renderers 1/2 compositors 0/1 display 0/1".
  std::string missing(int renderers, int compositors) const;
  std::vector<const Member*> alive(proto::Role r) const;  // by rank
  const Member* find(proto::Role r, uint32_t rank) const;
  Member* find(proto::Role r, uint32_t rank);
  // The display the frames go to: the alive display of lowest rank, or nullptr.
  const Member* display() const;
  // Who may send pieces and strips: alive renderers and compositors by the routing id of their
  // data connection (see StageLink::dataIdentity), under the current epoch.
  proto::Roster roster() const;
  uint32_t epoch() const { return epoch_; }
  void bumpEpoch() { ++epoch_; }

 private:
  std::map<std::pair<proto::Role, uint32_t>, Member> members_;
  uint32_t epoch_ = 0;
};

// The alive renderers and compositors, as the plans take them.
struct Workers;
Workers aliveWorkers(const Membership& members);
// Why a stage's Hello may not join this farm: another run (TESSERA_RUN), another scene (its
// sceneIdentity against the master's, naming the first line that differs), or an address its
// peers cannot reach (advertiseRefusal, on the farm's `endpoint_base`); "" when it may.
std::string helloRefusal(const proto::Hello& h, const std::string& run, const std::string& scene,
                         const std::string& endpoint_base);
// Why the address a stage advertises is one its peers cannot connect to (a compositor's host
// on a tcp farm, a renderer's swap socket), naming it: such a stage would make its healthy
// peers fail every frame. "" when it is fine.
std::string advertiseRefusal(const proto::Hello& h, const std::string& endpoint_base);

// Who frame `frame` waits for (`w`), e.g. "stats from renderer 1 (pid 1234) and strips from
// compositor 0 (pid 99)"; `culprit` gets the first of them (nullptr if none is a member), or,
// when that renderer's heartbeats say it awaits a binary-swap partner's piece of this frame,
// the renderer at the end of that chain of waits among those the frame waits for (the
// stalled one, not its silent partners; in a cycle of waits, the first). When the first is
// a compositor or the display and its heartbeats say whose piece or strips of this frame it
// lacks, that sender is the culprit although it reported: its parts were lost on the way (a
// failed link), and the farm can go on without it (never without the display). Only a
// receiver that is alive and heard from within the last second counts (a frozen one's last
// heartbeat is stale), and not one that names another sender than the last one a deadline
// dropped for it within a minute: a receiver whose senders fail one after the other is at
// fault itself. A named sender already lost is the culprit too: nobody is dropped, and the
// frame waits for its replacement. `named_by` (if given) gets the receiver that named it.
std::string describeWaiting(const Membership& members, uint64_t frame, const CreditWindow::Waiting& w,
                            Clock::time_point now, const Member** culprit, const Member** named_by = nullptr);

}  // namespace tessera::master
