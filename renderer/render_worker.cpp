#include "renderer/render_worker.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cstdint>
#include <exception>
#include <stdexcept>
#include <system_error>

namespace tessera::renderer {

RenderWorker::RenderWorker() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "render worker: eventfd");
  thread_ = std::thread([this] { loop(); });
}

RenderWorker::~RenderWorker() {
  {
    std::lock_guard lock(mu_);
    quit_ = true;
  }
  cv_.notify_one();
  thread_.join();
  close(fd_);
}

void RenderWorker::start(std::function<void()> job) {
  if (busy_) throw std::logic_error("render worker: a job is already running");
  busy_ = true;
  {
    std::lock_guard lock(mu_);
    job_ = std::move(job);
    done_ = false;
  }
  cv_.notify_one();
}

void RenderWorker::runAndWait(const std::function<void()>& job) {
  std::exception_ptr error;
  start([&] {
    try {
      job();
    } catch (...) {
      error = std::current_exception();
    }
  });
  {
    std::unique_lock lock(mu_);
    done_cv_.wait(lock, [&] { return done_; });
  }
  takeDone();
  if (error) std::rethrow_exception(error);
}

bool RenderWorker::takeDone() {
  if (!busy_) return false;
  {
    std::lock_guard lock(mu_);  // also orders the job's writes before the stage's reads
    if (!done_) return false;
  }
  uint64_t n;
  while (read(fd_, &n, sizeof n) == sizeof n) {
  }
  busy_ = false;
  return true;
}

void RenderWorker::loop() {
  std::unique_lock lock(mu_);
  for (;;) {
    cv_.wait(lock, [&] { return quit_ || job_; });
    if (!job_) return;  // quit with nothing to do
    auto job = std::move(job_);
    job_ = nullptr;
    lock.unlock();
    job();
    lock.lock();
    done_ = true;
    const uint64_t one = 1;
    if (write(fd_, &one, sizeof one) != sizeof one) {
    }  // the counter cannot overflow: one write per job
    done_cv_.notify_all();
  }
}

}  // namespace tessera::renderer
