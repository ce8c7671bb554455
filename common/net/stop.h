// SIGINT/SIGTERM → a flag that every stage's run loop checks, so processes stop cleanly.
#pragma once
#include <atomic>

namespace tessera {

// Installs the handlers (once) and returns the flag they set.
const std::atomic<bool>& installStopSignals();

}  // namespace tessera
