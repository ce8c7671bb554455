// A stage's sends of frame data to a receiver that stopped reading (its process dead or
// stopped, its link cut): they must give up, so that the stage goes on with its other frames.
// A renderer once blocked for good once its queue to a dead compositor was full.
#include <gtest/gtest.h>

#include <chrono>
#include <vector>

#include "common/clock.h"
#include "common/net/transport.h"
#include "tests/common/temp_dir.h"

namespace tessera {
namespace {

TEST(DataSender, GivesUpOnAReceiverThatStoppedReading) {
  test::TempDir dir("data_sender");
  zmq::context_t ctx;
  const std::string endpoint = "ipc://" + dir.file("receiver");
  zmq::socket_t receiver = makeSocket(ctx, zmq::socket_type::router);
  receiver.set(zmq::sockopt::rcvbuf, 64 << 10);
  receiver.bind(endpoint);  // never read: its queue and the socket's buffers fill, then the sender's
  zmq::socket_t sender = connectDataSender(ctx, endpoint, "renderer-1");
  const std::vector<std::byte> part(256 << 10);
  int sent = 0;
  double gave_up_after_ms = -1;
  for (int i = 0; i < 1000 && gave_up_after_ms < 0; ++i) {
    const auto t0 = Clock::now();
    if (sendBytes(sender, std::vector<std::byte>(part))) ++sent;
    else gave_up_after_ms = msSince(t0);
  }
  ASSERT_GE(gave_up_after_ms, 0) << "all " << sent << " sends went through";
  EXPECT_GE(sent, 64) << "the sender's own queue takes 64 parts before any send waits";
  EXPECT_GE(gave_up_after_ms, 0.9 * kDataSendTimeout.count());
  EXPECT_LT(gave_up_after_ms, kDataSendTimeout.count() + 2000.0);
}

}  // namespace
}  // namespace tessera
