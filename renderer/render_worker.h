// The thread a renderer casts its rays on, one job at a time, while the stage's own thread
// keeps its sockets: a binary swap's rounds advance, and the master's messages are taken,
// while the next frame renders. A finished job makes fd() readable, so the stage's poll
// wakes for it as for a message. Every volume render of a renderer runs here, also those
// the stage waits for (runAndWait), so that a backend's thread-bound state (osmesa's GL
// context) is made, used and released on one thread.
#pragma once
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace tessera::renderer {

class RenderWorker {
 public:
  RenderWorker();
  ~RenderWorker();  // waits for the job in progress
  RenderWorker(const RenderWorker&) = delete;
  RenderWorker& operator=(const RenderWorker&) = delete;

  // Runs `job` on the worker's thread; the worker must be idle. The job must not throw.
  void start(std::function<void()> job);
  // Runs `job` on the worker's thread and waits for it; rethrows what it threw. The worker
  // must be idle.
  void runAndWait(const std::function<void()>& job);
  // True while a job runs or its end has not been taken.
  bool busy() const { return busy_; }
  // True once when the job has ended (after that the worker is idle); its effects are visible.
  bool takeDone();
  int fd() const { return fd_; }  // readable while an ended job waits to be taken

 private:
  void loop();

  int fd_ = -1;
  bool busy_ = false;  // the stage thread's view
  std::mutex mu_;
  std::condition_variable cv_, done_cv_;
  std::function<void()> job_;
  bool done_ = false, quit_ = false;
  std::thread thread_;
};

}  // namespace tessera::renderer
