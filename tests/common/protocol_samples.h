// Sample messages for the protocol tests (every field set to a non-default value) and
// the tools to damage them: little-endian pokes and resealing the header.
#pragma once
#include <span>
#include <vector>

#include "common/wire/protocol.h"

namespace tessera::proto::test {

using Bytes = std::vector<std::byte>;

inline FrameParams sampleParams() {
  FrameParams p;
  p.frame = 42;
  p.epoch = 3;
  p.camera.eye = {1.5, -2, 3.25};
  p.camera.fov = 45;
  p.quality = {QualityName::Fast, 1.0 / 128, 0.95, true, false, true};
  p.width = 640;
  p.height = 480;
  p.codec = Codec::Lz4;
  p.format = PixelFormat::RGBA16F;
  p.regions = {{0, {0, 0, 640, 240}, "ipc:///tmp/c0"}, {1, {0, 240, 640, 240}, "tcp://127.0.0.1:5601"}};
  p.display_endpoint = "ipc:///tmp/display";
  p.first_wanted = 40;
  p.input_seq = 77;
  p.input_first = 70;
  p.interactive = true;
  p.step = 12345;
  p.next_step = 12344;
  p.window = {0.3125, 0.25};
  p.work = SortLastWork{{{0, {{0, 0, 0}, {128, 256, 256}}}, {1, {{128, 0, 0}, {256, 256, 256}}}, {1, {{0, 0, 0}, {1, 1, 1}}}},
                        {2, 0, 1}, {}};
  return p;
}

inline FrameParams sampleSortFirstParams() {
  FrameParams p = sampleParams();
  p.work = SortFirstWork{{{0, 1, {0, 0, 320, 240}}, {1, 0, {320, 0, 320, 1}}}};
  return p;
}

inline Framebuffer sampleFramebuffer() {
  Framebuffer f;
  f.frame = 5;
  f.epoch = 2;
  f.renderer = 1;
  f.width = 13;
  f.height = 7;
  f.pixels.resize(13 * 7 * 4);
  for (size_t i = 0; i < f.pixels.size(); ++i) f.pixels[i] = std::byte(uint8_t(i % 11 == 0 ? i : 0));
  f.render_ms = 2.5;
  return f;
}

inline Piece samplePiece(PixelFormat f) {
  Piece p;
  p.frame = 7;
  p.epoch = 3;
  p.renderer = 3;
  p.brick = 2;
  p.region = {0, 100, 64, 32};
  p.active = {10, 105, 20, 9};
  p.format = f;
  p.pixels.resize(size_t(p.active.area()) * bytesPerPixel(f));
  for (size_t i = 0; i < p.pixels.size(); ++i) p.pixels[i] = std::byte(uint8_t(i * 7 / 5));
  p.render_ms = 12.5;
  p.encode_ms = 0.25;
  return p;
}

inline Strips sampleStrips() {
  Strips s;
  s.frame = 9;
  s.epoch = 3;
  s.render_ms = 4.5;
  s.sender = 1;
  s.stream.assign(1000, 0);
  for (size_t i = 0; i < 300; ++i) s.stream[i] = uint8_t(i);
  s.composite_ms = 3;
  s.encode_ms = 1;
  s.active_pixels = 123456789012ull;
  return s;
}

// Independent Adler-32 so the test checks the wire format rather than trusting the code.
inline uint32_t adler(std::span<const std::byte> p) {
  uint32_t a = 1, b = 0;
  for (std::byte x : p) {
    a = (a + uint8_t(x)) % 65521;
    b = (b + a) % 65521;
  }
  return (b << 16) | a;
}
inline void putLE(Bytes& m, size_t off, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) m[off + i] = std::byte(uint8_t(v >> (8 * i)));
}
// Re-signs a (possibly edited) message so only the field under test is wrong.
inline void reseal(Bytes& m) {
  putLE(m, 28, m.size() - kHeaderSize, 4);
  putLE(m, 32, adler(std::span(m).subspan(kHeaderSize)), 4);
}

}  // namespace tessera::proto::test
