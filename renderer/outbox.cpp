#include "renderer/outbox.h"

#include <algorithm>

#include "common/net/transport.h"

namespace tessera::renderer {

void Outbox::send(const std::string& endpoint, std::vector<std::byte>&& bytes) {
  auto it = pushes_.find(endpoint);
  if (it == pushes_.end()) {
    try {
      it = pushes_.emplace(endpoint, connectDataSender(ctx_, endpoint, identity_)).first;
    } catch (const zmq::error_t& e) {  // an address ZeroMQ refuses: this part is lost, not the others
      return unsent_.drop(0, fmt::format("part not sent to '{}': cannot connect ({})", endpoint, e.what()));
    }
  }
  if (!sendBytes(it->second, std::move(bytes)))
    unsent_.drop(0, fmt::format("part not sent to {}: the queue to it stayed full for {} ms", endpoint,
                                kDataSendTimeout.count()));
}

void Outbox::keepOnly(const proto::FrameParams& p, const proto::SortLastWork& work) {
  std::erase_if(pushes_, [&](const auto& kv) {
    const std::string& e = kv.first;
    return e != p.display_endpoint &&
           std::none_of(p.regions.begin(), p.regions.end(), [&](const auto& r) { return r.endpoint == e; }) &&
           std::none_of(work.swap.begin(), work.swap.end(), [&](const auto& s) { return s.endpoint == e; });
  });
}

}  // namespace tessera::renderer
