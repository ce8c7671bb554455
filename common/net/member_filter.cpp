// Data-socket admission by routing id (see member_filter.h).
#include "common/net/member_filter.h"

namespace tessera {

MemberFilter::MemberFilter(proto::Role senders, size_t max_waiting, size_t max_waiting_bytes)
    : senders_(senders), max_waiting_(max_waiting), max_waiting_bytes_(max_waiting_bytes) {}

std::optional<uint32_t> MemberFilter::rankOf(const std::string& identity) const {
  auto it = ranks_.find(identity);
  if (it == ranks_.end()) return std::nullopt;
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
  ranks_.clear();
  for (const auto& m : roster.members)
    if (m.role == senders_) ranks_[m.identity] = m.rank;
  std::vector<Held> admitted;
  for (auto& h : held_) {
    if (ranks_.count(h.identity)) admitted.push_back(std::move(h));
    else ++dropped;
  }
  held_.clear();
  held_bytes_ = 0;
  return admitted;
}

}  // namespace tessera
