// The one clock for durations: steady (never jumps with the wall clock), read as milliseconds.
#pragma once
#include <chrono>

namespace tessera {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

}  // namespace tessera
