// Thread fan-out (see parallel.h).
#include "common/parallel.h"

#include <algorithm>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tessera {

unsigned threadCount(int requested, long long max_useful) {
  long long t = requested > 0 ? requested : std::max(1u, std::thread::hardware_concurrency());
  return (unsigned)std::max(1LL, std::min(t, max_useful));
}

void runParts(unsigned parts, const std::function<void(unsigned part)>& body) {
  std::mutex mu;
  std::exception_ptr error;
  auto guarded = [&](unsigned part) {
    try {
      body(part);
    } catch (...) {
      std::lock_guard lock(mu);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned p = 1; p < parts; ++p) pool.emplace_back(guarded, p);
  guarded(0);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

void parallelRanges(long long n, unsigned parts, const std::function<void(long long begin, long long end)>& body) {
  parts = (unsigned)std::max(1LL, std::min<long long>(parts, n));
  runParts(parts, [&](unsigned p) { body(n * p / parts, n * (p + 1) / parts); });
}

}  // namespace tessera
