// Data-socket admission by routing id (see member_filter.h).
#include "common/net/member_filter.h"

#include <algorithm>

namespace tessera {

MemberFilter::MemberFilter(std::vector<proto::Role> senders, size_t max_waiting, size_t max_waiting_bytes)
    : senders_(std::move(senders)), max_waiting_(max_waiting), max_waiting_bytes_(max_waiting_bytes) {}

std::optional<MemberFilter::Sender> MemberFilter::senderOf(const std::string& identity) const {
  auto it = members_.find(identity);
  if (it == members_.end()) return std::nullopt;
  return it->second;
}

bool MemberFilter::hold(std::string identity, zmq::message_t&& body) {
  if (held_.size() >= max_waiting_ || held_bytes_ + body.size() > max_waiting_bytes_) return false;
  held_bytes_ += body.size();
  held_.push_back({std::move(identity), std::move(body)});
  return true;
}

std::vector<MemberFilter::Held> MemberFilter::setRoster(const proto::Roster& roster, uint64_t& dropped) {
  dropped = 0;
  if (have_roster_ && roster.epoch < epoch_) return {};
  have_roster_ = true;
  epoch_ = roster.epoch;
  members_.clear();
  for (const auto& m : roster.members)
    if (std::find(senders_.begin(), senders_.end(), m.role) != senders_.end()) members_[m.identity] = {m.role, m.rank};
  std::vector<Held> admitted;
  for (auto& h : held_) {
    if (members_.count(h.identity)) admitted.push_back(std::move(h));
    else ++dropped;
  }
  held_.clear();
  held_bytes_ = 0;
  return admitted;
}

}  // namespace tessera
