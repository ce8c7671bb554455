// The main of a command-line tool: runs it, and turns any exception into one line on
// stderr naming the tool, and exit code 1.
#pragma once
#include <cstdio>
#include <exception>

namespace tessera {

template <class Run>
int toolMain(const char* name, Run run) {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace tessera
