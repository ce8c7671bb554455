// Time to present one 1024x1024 frame in the display window (upload, scale, status line,
// swap), with SDL's default renderer and with its software renderer, on a private Xvfb
// server. Run: build/bin/display_bench (needs the Debian package xvfb).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "display/sink.h"
#include "tests/display/xvfb.h"

namespace {

using namespace tessera;

void presentBench(benchmark::State& state, const char* driver) {
  if (*driver) setenv("SDL_RENDER_DRIVER", driver, 1);
  else unsetenv("SDL_RENDER_DRIVER");
  std::unique_ptr<display::Sink> sink;
  try {
    sink = display::makeWindowSink(1024, 1024, "tessera bench");
  } catch (const std::runtime_error& e) {
    state.SkipWithError(e.what());
    return;
  }
  Image8 frame(1024, 1024);
  for (size_t i = 0; i < frame.px.size(); ++i) frame.px[i] = (uint8_t)(i * 7 / 5);
  for (size_t i = 3; i < frame.px.size(); i += 4) frame.px[i] = 255;
  uint64_t k = 0;
  for (auto _ : state) {
    sink->present(frame, {k++, "fps 10.0 latency 120 ms render 50 composite 8 display 6"});
    sink->poll();
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (!display::testing::onPath("Xvfb")) {
    std::fprintf(stderr, "display_bench: Xvfb not installed (Debian package xvfb)\n");
    return 77;
  }
  display::testing::Xvfb xvfb;
  std::string err;
  if (!xvfb.start(err)) {
    std::fprintf(stderr, "display_bench: %s\n", err.c_str());
    return 1;
  }
  setenv("DISPLAY", xvfb.display().c_str(), 1);
  unsetenv("WAYLAND_DISPLAY");
  benchmark::RegisterBenchmark("present_1024/default", presentBench, "")->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::RegisterBenchmark("present_1024/software", presentBench, "software")
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  xvfb.stop();
  return 0;
}
