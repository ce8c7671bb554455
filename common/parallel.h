// The one way Tessera fans work out over threads. The calling thread takes part; the others
// are plain std::threads joined before return: blocking, never spinning, because on a shared
// 2-core machine a spinning pool stalls whenever another process holds a core. The first
// exception thrown by any part is rethrown in the caller once every part has stopped.
#pragma once
#include <functional>

namespace tessera {

// Threads to use: `requested` if > 0, else the hardware concurrency; clamped to [1, max_useful].
unsigned threadCount(int requested, long long max_useful);

// Calls body(part) for every part in [0, parts), each on its own thread (part 0 on the caller's).
void runParts(unsigned parts, const std::function<void(unsigned part)>& body);

// Splits [0, n) into `parts` contiguous ranges and calls body(begin, end) for each, in parallel.
void parallelRanges(long long n, unsigned parts, const std::function<void(long long begin, long long end)>& body);

}  // namespace tessera
