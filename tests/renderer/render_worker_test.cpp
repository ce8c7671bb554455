// The renderer's worker thread (renderer/render_worker.h): a job runs on another thread, its
// end makes the descriptor readable for the stage's poll and is taken once, a job the stage
// waits for rethrows on the stage's thread, and destroying the worker waits for a job in progress.
#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <stdexcept>
#include <chrono>
#include <thread>

#include "renderer/render_worker.h"

namespace tessera::renderer {
namespace {

bool readable(int fd, int ms) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, ms) == 1 && (p.revents & POLLIN);
}

TEST(RenderWorker, AJobRunsOnItsThreadAndItsEndIsTakenOnce) {
  RenderWorker w;
  EXPECT_FALSE(w.busy());
  EXPECT_FALSE(w.takeDone());
  std::thread::id ran_on;
  std::atomic<bool> go{false};
  w.start([&] {
    while (!go) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ran_on = std::this_thread::get_id();
  });
  EXPECT_TRUE(w.busy());
  EXPECT_FALSE(readable(w.fd(), 20)) << "the job has not ended";
  EXPECT_FALSE(w.takeDone());
  go = true;
  ASSERT_TRUE(readable(w.fd(), 5000));
  EXPECT_TRUE(w.takeDone());
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_FALSE(w.busy());
  EXPECT_FALSE(w.takeDone()) << "taken once";
  EXPECT_FALSE(readable(w.fd(), 0));
  w.start([] {});
  EXPECT_THROW(w.start([] {}), std::logic_error) << "one job at a time";
}

TEST(RenderWorker, DestroyingItWaitsForTheJobInProgress) {
  std::atomic<bool> finished{false};
  {
    RenderWorker w;
    w.start([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      finished = true;
    });
  }
  EXPECT_TRUE(finished);
}

TEST(RenderWorker, RunAndWaitRunsOnItsThreadAndRethrows) {
  RenderWorker w;
  std::thread::id ran_on;
  w.runAndWait([&] { ran_on = std::this_thread::get_id(); });
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_FALSE(w.busy());
  EXPECT_FALSE(readable(w.fd(), 0)) << "its end was taken";
  EXPECT_THROW(w.runAndWait([] { throw std::runtime_error("bad frame"); }), std::runtime_error);
  EXPECT_FALSE(w.busy()) << "a job that threw leaves the worker idle";
  int runs = 0;
  w.runAndWait([&] { ++runs; });
  EXPECT_EQ(runs, 1);
}

}  // namespace
}  // namespace tessera::renderer
