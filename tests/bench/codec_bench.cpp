// Codec throughput and ratio on a 1024x1024 rgba8 frame shaped like a volume rendering
// (25% of pixels non-empty, smooth colours) and on an all-empty frame, and the PNG file the
// headless display writes for every frame. Single thread.
// Counters: bytes_per_second = raw MB/s (both directions), ratio = encoded / raw size.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <cstdint>
#include <string>
#include <vector>

#include "common/image.h"
#include "common/io/image_io.h"
#include "common/wire/codec.h"
#include "common/wire/protocol.h"

namespace {

constexpr int kSide = 1024;

// A soft-edged disc covering 25% of the frame: premultiplied colour that varies smoothly,
// alpha falling off towards the rim, plus 1-LSB sampling noise as a real ray caster has.
std::vector<std::byte> renderLikeFrame() {
  std::vector<std::byte> px(size_t(4) * kSide * kSide);
  const double radius = kSide * std::sqrt(0.25 / M_PI), c = kSide / 2.0;
  uint32_t noise = 12345;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const double r = std::hypot(x - c, y - c) / radius;
      if (r >= 1) continue;
      noise = noise * 1664525u + 1013904223u;
      const int dither = int(noise >> 31);
      const double a = 0.35 + 0.65 * (1 - r * r);
      const double shade = 0.5 + 0.5 * std::sin(x * 0.013) * std::cos(y * 0.017);
      auto q = [&](double v) { return std::byte(uint8_t(std::min(255.0, 255 * v * a) + dither * (v > 0))); };
      std::byte* p = &px[4 * (size_t(y) * kSide + x)];
      p[0] = q(0.9 * shade);
      p[1] = q(0.4 + 0.3 * shade);
      p[2] = q(1 - shade);
      p[3] = std::byte(uint8_t(255 * a));
    }
  }
  return px;
}

const std::vector<std::byte>& frame(bool empty) {
  static const std::vector<std::byte> render = renderLikeFrame();
  static const std::vector<std::byte> blank(size_t(4) * kSide * kSide);
  return empty ? blank : render;
}

void setCounters(benchmark::State& state, size_t raw, size_t encoded) {
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(raw));
  state.counters["ratio"] = double(encoded) / double(raw);
}

void compressBench(benchmark::State& state, tessera::Codec c, bool empty) {
  const auto& raw = frame(empty);
  std::vector<std::byte> out;
  out.reserve(raw.size() * 2);
  for (auto _ : state) {
    out.clear();
    tessera::compressAppend(c, raw, out);
    benchmark::DoNotOptimize(out.data());
  }
  setCounters(state, raw.size(), out.size());
}

void decompressBench(benchmark::State& state, tessera::Codec c, bool empty) {
  const auto& raw = frame(empty);
  const auto enc = tessera::compress(c, raw);
  std::vector<std::byte> out(raw.size());
  for (auto _ : state) {
    auto r = tessera::decompressInto(c, enc, out);
    if (!r) state.SkipWithError(r.error().c_str());
    benchmark::DoNotOptimize(out.data());
  }
  if (out != raw) state.SkipWithError("round trip mismatch");
  setCounters(state, raw.size(), enc.size());
}

// Whole-message cost on top of the codec: framing, metadata, Adler-32 and validation.
tessera::proto::Piece framePiece() {
  tessera::proto::Piece p;
  p.region = p.active = {0, 0, kSide, kSide};
  p.pixels = frame(false);
  return p;
}

void encodePieceBench(benchmark::State& state, tessera::Codec c) {
  const auto piece = framePiece();
  size_t size = 0;
  for (auto _ : state) {
    auto msg = tessera::proto::encode(piece, 1, c);
    size = msg.size();
    benchmark::DoNotOptimize(msg.data());
  }
  setCounters(state, piece.pixels.size(), size);
}

void decodePieceBench(benchmark::State& state, tessera::Codec c) {
  const auto piece = framePiece();
  const auto msg = tessera::proto::encode(piece, 1, c);
  for (auto _ : state) {
    auto r = tessera::proto::decodePiece(msg);
    if (!r) state.SkipWithError(r.error().c_str());
    benchmark::DoNotOptimize(r->pixels.data());
  }
  setCounters(state, piece.pixels.size(), msg.size());
}

// The display's per-frame file: un-premultiply, filter, deflate, write (to /tmp).
void writePngBench(benchmark::State& state) {
  tessera::Image8 img(kSide, kSide);
  std::memcpy(img.px.data(), frame(false).data(), img.px.size());
  const std::string path = "/tmp/tessera-codec-bench-" + std::to_string(getpid()) + ".png";
  for (auto _ : state) tessera::writePng(path, img, std::nullopt);
  state.counters["bytes"] = double(std::filesystem::file_size(path));
  std::filesystem::remove(path);
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(img.px.size()));
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("write_png/render", writePngBench)->Unit(benchmark::kMillisecond)->UseRealTime();
  for (uint8_t i = 0; i < tessera::kCodecCount; ++i) {
    const auto c = tessera::Codec(i);
    for (bool empty : {false, true}) {
      const std::string tail = std::string(tessera::codecName(c)) + (empty ? "/empty" : "/render");
      // Wall time: on a shared 2-core machine CPU-time accounting is unreliable.
      benchmark::RegisterBenchmark(("compress/" + tail).c_str(), compressBench, c, empty)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
      benchmark::RegisterBenchmark(("decompress/" + tail).c_str(), decompressBench, c, empty)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }
  for (tessera::Codec c : {tessera::Codec::None, tessera::Codec::Lz4}) {
    const std::string name = std::string("/") + tessera::codecName(c) + "/render";
    benchmark::RegisterBenchmark(("encode_piece" + name).c_str(), encodePieceBench, c)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("decode_piece" + name).c_str(), decodePieceBench, c)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
