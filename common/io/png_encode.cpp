// PNG writing with ISA-L's deflate (igzip): the headless display writes every frame as PNG,
// and libpng can only compress through zlib. On codec_bench's 1024x1024 frame (AMD EPYC,
// AVX-512) libpng with zlib at its fastest setting took 13.3 ms and 364 KB, igzip level 1
// 3.6 ms and 420 KB (write_png/render). The container is what PNG specifies and every reader
// checks: signature, IHDR, IDAT (a zlib stream of filtered rows), IEND, each chunk with its
// CRC-32. Rows are filtered with Up (the row above subtracted), which suits rendered frames
// (runs of equal rows, smooth gradients) and is one subtraction a byte.
#include "common/io/png_encode.h"

#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace tessera {
namespace {

constexpr uint8_t kSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
constexpr uint8_t kFilterUp = 2;
// Filtered rows are handed to the compressor this many bytes at a time (a bounded copy,
// warm in cache, instead of a filtered copy of the whole image).
constexpr size_t kBlockBytes = 256 << 10;
// An IDAT chunk's length is 31 bits; large images get several.
constexpr size_t kMaxChunk = size_t{1} << 30;

void put32(std::vector<uint8_t>& out, uint32_t v) {
  const uint8_t b[4] = {uint8_t(v >> 24), uint8_t(v >> 16), uint8_t(v >> 8), uint8_t(v)};
  out.insert(out.end(), b, b + 4);
}

void chunk(std::vector<uint8_t>& out, const char type[4], const uint8_t* data, size_t n) {
  put32(out, (uint32_t)n);
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (n) out.insert(out.end(), data, data + n);
  put32(out, crc32_gzip_refl(0, out.data() + start, n + 4));  // over type and data
}

}  // namespace

std::vector<uint8_t> encodePngRgba(const std::string& what, int w, int h, const uint8_t* rgba) {
  if (w <= 0 || h <= 0) throw std::runtime_error(what + ": cannot write an empty image as PNG");
  const size_t stride = (size_t)w * 4;
  if (stride + 1 > std::numeric_limits<uint32_t>::max())
    throw std::runtime_error(what + ": " + std::to_string(w) + " pixels are too wide a row for PNG");
  // Kept per thread: the compressor's tables (~280 KB) and the buffers, reused frame after
  // frame; a huge image's buffers are let go afterwards (also when this throws).
  thread_local std::vector<uint8_t> level_buf(ISAL_DEF_LVL1_DEFAULT), block, z;
  isal_zstream s;
  isal_deflate_init(&s);
  s.level = 1;
  s.level_buf = level_buf.data();
  s.level_buf_size = (uint32_t)level_buf.size();
  s.gzip_flag = IGZIP_ZLIB;
  s.flush = NO_FLUSH;
  struct Trim {
    ~Trim() {
      if (block.size() > kBlockBytes + (1 << 20)) block = {};
      if (z.size() > (size_t{64} << 20)) z = {};
    }
  } trim;
  const int64_t rows_per_block = (int64_t)std::max<size_t>(1, kBlockBytes / (stride + 1));
  block.resize((stride + 1) * (size_t)rows_per_block);
  if (z.size() < stride * h / 4 + 65536) z.resize(stride * h / 4 + 65536);
  size_t used = 0;
  for (int64_t y0 = 0; y0 < h; y0 += rows_per_block) {
    const int64_t n = std::min<int64_t>(rows_per_block, h - y0);
    for (int64_t i = 0; i < n; ++i) {
      const int64_t y = y0 + i;
      uint8_t* f = &block[(stride + 1) * i];
      const uint8_t* row = rgba + stride * y;
      f[0] = kFilterUp;
      if (y == 0) {
        std::memcpy(f + 1, row, stride);  // above the first row counts as zeros
      } else {
        const uint8_t* above = row - stride;
        for (size_t x = 0; x < stride; ++x) f[1 + x] = (uint8_t)(row[x] - above[x]);
      }
    }
    s.next_in = block.data();
    s.avail_in = (uint32_t)((stride + 1) * n);
    s.end_of_stream = y0 + n == h;
    for (;;) {
      if (z.size() - used < 65536) z.resize(std::max(2 * z.size(), used + 65536));
      s.next_out = z.data() + used;
      s.avail_out = (uint32_t)std::min<size_t>(z.size() - used, std::numeric_limits<uint32_t>::max());
      if (isal_deflate(&s) != COMP_OK) throw std::runtime_error(what + ": PNG compression failed");
      used = (size_t)(s.next_out - z.data());
      if (s.end_of_stream ? s.internal_state.state == ZSTATE_END : s.avail_in == 0) break;
    }
  }
  std::vector<uint8_t> out(kSignature, kSignature + 8);
  out.reserve(8 + 25 + used + (used / kMaxChunk + 1) * 12 + 12);
  const uint8_t ihdr[13] = {uint8_t(w >> 24), uint8_t(w >> 16), uint8_t(w >> 8), uint8_t(w),
                            uint8_t(h >> 24), uint8_t(h >> 16), uint8_t(h >> 8), uint8_t(h),
                            8 /* bits */, 6 /* RGBA */, 0 /* deflate */, 0 /* adaptive filters */, 0 /* no interlace */};
  chunk(out, "IHDR", ihdr, sizeof ihdr);
  for (size_t at = 0; at < used; at += kMaxChunk) chunk(out, "IDAT", z.data() + at, std::min(kMaxChunk, used - at));
  chunk(out, "IEND", nullptr, 0);
  return out;
}

}  // namespace tessera
