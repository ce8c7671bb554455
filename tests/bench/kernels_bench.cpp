// Renderer and compositing kernels: trilinear sampling, ray casting of small tiles (fast and
// reference paths), min-max block classification, a time step's caster preparation, and compositing / packing of 1024x1024
// images (the target: two renderers' rgba8 pieces composited in under 5 ms).
// Counters: items_per_second = samples, blocks or pixels; bytes_per_second = input bytes.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "common/image.h"
#include "common/wire/pixels.h"
#include "common/scene.h"
#include "compositor/over.h"
#include "renderer/volume/kernels.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/raycaster.h"
#include "renderer/volume/tf_table.h"

namespace {

using namespace tessera;
constexpr int kSide = 1024;

std::shared_ptr<const Volume> shell(int size) {
  return std::make_shared<const Volume>(generateVolume(GeneratorSpec{"hollow-shell", size, 1, {1, 1, 1}}));
}

// A 1024^2 premultiplied image like one renderer's half of a volume rendering: a soft disc
// whose alpha falls off to the rim, offset so two of them overlap partly.
ImageF discImage(double cx, double cy, float tint) {
  ImageF img(kSide, kSide);
  const double radius = kSide * 0.4;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (radius * radius);
      if (r2 >= 1) continue;
      const float a = float(0.2 + 0.7 * (1 - r2));
      float* p = img.at(x, y);
      p[0] = a * tint;
      p[1] = a * 0.5f;
      p[2] = a * (1 - tint);
      p[3] = a;
    }
  return img;
}

const ImageF& front() {
  static const ImageF img = discImage(kSide * 0.45, kSide * 0.5, 0.9f);
  return img;
}
const ImageF& back() {
  static const ImageF img = discImage(kSide * 0.55, kSide * 0.5, 0.2f);
  return img;
}
const Rect kFull{0, 0, kSide, kSide};

void BM_SampleTrilinear(benchmark::State& state) {
  const auto vol = shell(int(state.range(0)));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, double(state.range(0) - 1));
  std::vector<double> pts(3 * 4096);
  for (double& p : pts) p = u(rng);
  double sum = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < pts.size(); i += 3) sum += renderer::sampleTrilinear(*vol, pts[i], pts[i + 1], pts[i + 2]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size() / 3));
}
BENCHMARK(BM_SampleTrilinear)->Arg(64)->Arg(256);

// One thread renders a 128x128 tile of a 64^3 shell; items = samples taken (skipped ones
// are free by design, so samples/s alone would flatter skipping: compare real_time too).
void BM_RenderTile(benchmark::State& state, const char* quality, bool skip) {
  const auto vol = shell(64);
  const Scene sc = defaultScene();
  const renderer::Raycaster rc(vol, sc.tf);
  renderer::RenderOptions opt;
  opt.quality = namedQuality(quality);
  opt.quality.skip_empty = skip && !opt.quality.reference;
  opt.threads = 1;
  const int side = opt.quality.reference ? 32 : 128;
  uint64_t samples = 0;
  for (auto _ : state) {
    renderer::RenderStats st;
    ImageF img = rc.render(sc.camera, side, side, renderer::wholeVolume(*vol), opt, &st);
    benchmark::DoNotOptimize(img.px.data());
    samples += st.samples;
  }
  state.SetItemsProcessed(int64_t(samples));
  state.counters["pixels"] = double(side) * side;
}
BENCHMARK_CAPTURE(BM_RenderTile, default_skip, "default", true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderTile, default_noskip, "default", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderTile, fast_skip, "fast", true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderTile, reference_32px, "reference", false)->Unit(benchmark::kMillisecond);

// Ray set-up of a 1024^2 frame, eight rays at a time (raySpans, the CPU's instruction set):
// a farm's renderer sets up every ray of its brick's footprint, once per brick it renders.
// The 256^3 volume whole, and the front upper quarter a renderer of four holds.
void BM_RaySpans(benchmark::State& state, bool quarter) {
  const Scene sc = defaultScene();
  Volume v;
  v.dims = {256, 256, 256};
  const renderer::VolumeGeometry g(v);
  const RayGenerator gen(sc.camera, kSide, kSide);
  const BrickBox brick = quarter ? BrickBox{{0, 128, 128}, {256, 256, 256}} : BrickBox{{0, 0, 0}, {256, 256, 256}};
  const renderer::SpanRow row(gen, g, brick, brick, 1.0 / 256, false);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo[renderer::kSpanLanes], hi[renderer::kSpanLanes];
  std::fill_n(lo, renderer::kSpanLanes, -kInf);
  std::fill_n(hi, renderer::kSpanLanes, kInf);
  renderer::RaySpan spans[renderer::kSpanLanes];
  int64_t hits = 0;
  for (auto _ : state)
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; x += renderer::kSpanLanes)
        hits += std::popcount(renderer::raySpans(row, x, y, renderer::kSpanLanes, lo, hi, spans));
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.counters["hits"] = double(hits) / double(state.iterations());
}
BENCHMARK_CAPTURE(BM_RaySpans, whole, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RaySpans, quarter, true)->Unit(benchmark::kMillisecond);

// Which 8^3 blocks of a 256^3 volume are empty under the default transfer function:
// exact maxAlpha over each block's value range, and the table-based test the kernels use.
void BM_BlockClassify(benchmark::State& state, bool table) {
  const auto vol = shell(256);
  const renderer::MinMaxHierarchy h(*vol);
  const TransferFunction tf = defaultScene().tf;
  uint64_t blocks = 0;
  for (auto _ : state) {
    const auto e = table ? h.classify([&](float lo, float hi) { return renderer::TfTable::rangeIsEmpty(tf, lo, hi); })
                         : h.classify([&](float lo, float hi) { return tf.maxAlpha(lo, hi) == 0; });
    benchmark::DoNotOptimize(e.empty_blocks);
    const auto d = h.dims(0);
    blocks += uint64_t(d[0]) * d[1] * d[2];
  }
  state.SetItemsProcessed(int64_t(blocks));
}
BENCHMARK_CAPTURE(BM_BlockClassify, maxAlpha, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BlockClassify, tfTable, true)->Unit(benchmark::kMillisecond);

// Float "over" of a second 1024^2 image onto a first (dst reset by copy, timed separately).
// What a time step costs a renderer before it can ray cast it, besides reading the file:
// the caster for one of two renderers' share of an N^3 step (N/2 x N x N floats, N = 256 and
// 512): the bricked uint16 copy, the min-max hierarchy, the non-finite check and the
// classification. Counter: bytes_per_second = float input bytes.
void BM_PrepareStep(benchmark::State& state) {
  const int n = (int)state.range(0);
  const auto whole = shell(n);
  auto half = std::make_shared<Volume>();
  half->dims = {n / 2, n, n};
  half->values.resize(half->voxelCount());
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n / 2; ++x) half->values[half->index(x, y, z)] = whole->at(x, y, z);
  const TransferFunction tf = defaultScene().tf;
  for (auto _ : state) {
    renderer::Raycaster rc(half, tf);
    benchmark::DoNotOptimize(&rc);
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(half->values.size() * sizeof(float)));
}
BENCHMARK(BM_PrepareStep)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond);

void BM_CompositeOverF32(benchmark::State& state) {
  ImageF dst = front();
  for (auto _ : state) {
    compositeOver(dst, back(), kFull);
    benchmark::DoNotOptimize(dst.px.data());
    state.PauseTiming();
    dst.px = front().px;
    state.ResumeTiming();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.SetBytesProcessed(int64_t(state.iterations()) * kSide * kSide * 16);
}
BENCHMARK(BM_CompositeOverF32)->Unit(benchmark::kMillisecond);

// One wire piece "under" the float buffer (as the compositor does per renderer).
void BM_CompositeUnder(benchmark::State& state, proto::PixelFormat f) {
  const auto piece = packPixels(back(), kFull, f);
  ImageF dst = front();
  for (auto _ : state) {
    compositeUnder(dst, kFull, piece, kFull, f);
    benchmark::DoNotOptimize(dst.px.data());
    state.PauseTiming();
    dst.px = front().px;
    state.ResumeTiming();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(piece.size()));
}
BENCHMARK_CAPTURE(BM_CompositeUnder, rgba8, proto::PixelFormat::RGBA8)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CompositeUnder, rgba16f, proto::PixelFormat::RGBA16F)->Unit(benchmark::kMillisecond);

// The number: a compositor's whole frame for two renderers' 1024^2 pieces: clear
// the float buffer, composite both pieces, quantize to rgba8 and count active pixels.
void BM_CompositeRegionTwoPieces(benchmark::State& state, proto::PixelFormat f) {
  std::vector<proto::Piece> pieces(2);
  pieces[0].active = pieces[1].active = kFull;
  pieces[0].format = pieces[1].format = f;
  pieces[0].pixels = packPixels(front(), kFull, f);
  pieces[1].pixels = packPixels(back(), kFull, f);
  const std::vector<int> order{0, 1};
  std::vector<float> row;
  Image8 out(kSide, kSide);
  for (auto _ : state) benchmark::DoNotOptimize(compositor::compositeRegion(kFull, order, pieces, row, out));
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(2 * pieces[0].pixels.size()));
}
BENCHMARK_CAPTURE(BM_CompositeRegionTwoPieces, rgba8, proto::PixelFormat::RGBA8)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CompositeRegionTwoPieces, rgba16f, proto::PixelFormat::RGBA16F)->Unit(benchmark::kMillisecond);

void BM_PackPixels(benchmark::State& state, proto::PixelFormat f) {
  for (auto _ : state) {
    auto bytes = packPixels(front(), kFull, f);
    benchmark::DoNotOptimize(bytes.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.SetBytesProcessed(int64_t(state.iterations()) * kSide * kSide * 16);
}
BENCHMARK_CAPTURE(BM_PackPixels, rgba8, proto::PixelFormat::RGBA8)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PackPixels, rgba16f, proto::PixelFormat::RGBA16F)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
