// Codec implementations over liblzo2, liblz4 and libzstd. Per-thread scratch state
// (LZO work memory, zstd contexts) keeps every call thread-safe without locks.
#include "common/wire/codec.h"

#include <lz4.h>
#include <lzo/lzo1x.h>
#include <zstd.h>

#include <climits>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace tessera {
namespace {

void initLzoOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (lzo_init() != LZO_E_OK) throw std::runtime_error("lzo_init failed (liblzo2 ABI mismatch)");
  });
}

// LZO1X worst case expansion per the liblzo2 documentation.
size_t lzoBound(size_t n) { return n + n / 16 + 64 + 3; }

struct ZstdDeleter {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

// Never hand a null pointer to a C API for an empty buffer.
unsigned char* bytesOf(std::span<std::byte> s) {
  static thread_local unsigned char dummy;
  return s.empty() ? &dummy : reinterpret_cast<unsigned char*>(s.data());
}
const unsigned char* bytesOf(std::span<const std::byte> s) {
  static const unsigned char dummy = 0;
  return s.empty() ? &dummy : reinterpret_cast<const unsigned char*>(s.data());
}

size_t compressLzo(std::span<const std::byte> raw, unsigned char* dst) {
  initLzoOnce();
  static thread_local std::unique_ptr<unsigned char[]> work(new unsigned char[LZO1X_1_MEM_COMPRESS]);
  lzo_uint out_len = 0;
  lzo1x_1_compress(bytesOf(raw), raw.size(), dst, &out_len, work.get());  // cannot fail
  return out_len;
}

size_t compressLz4(std::span<const std::byte> raw, unsigned char* dst, size_t cap) {
  if (raw.size() > LZ4_MAX_INPUT_SIZE) throw std::length_error("lz4: input larger than 2 GB");
  int n = LZ4_compress_default(reinterpret_cast<const char*>(bytesOf(raw)), reinterpret_cast<char*>(dst),
                               static_cast<int>(raw.size()), static_cast<int>(cap));
  if (n <= 0) throw std::logic_error("lz4: compression failed despite LZ4_compressBound");
  return static_cast<size_t>(n);
}

size_t compressZstd(std::span<const std::byte> raw, unsigned char* dst, size_t cap) {
  static thread_local std::unique_ptr<ZSTD_CCtx, ZstdDeleter> ctx(ZSTD_createCCtx());
  size_t n = ZSTD_compressCCtx(ctx.get(), dst, cap, bytesOf(raw), raw.size(), 1);
  if (ZSTD_isError(n)) throw std::logic_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  return n;
}

size_t bound(Codec c, size_t n) {
  switch (c) {
    case Codec::None: return n;
    case Codec::Lzo: return lzoBound(n);
    case Codec::Lz4: return n > LZ4_MAX_INPUT_SIZE ? n : static_cast<size_t>(LZ4_compressBound(static_cast<int>(n)));
    case Codec::Zstd: return ZSTD_compressBound(n);
  }
  throw std::invalid_argument("unknown codec " + std::to_string(static_cast<int>(c)));
}

std::string sizeMismatch(const char* name, size_t got, size_t want) {
  return std::string(name) + ": decoded " + std::to_string(got) + " bytes, expected " + std::to_string(want);
}

}  // namespace

const char* codecName(Codec c) {
  switch (c) {
    case Codec::None: return "none";
    case Codec::Lzo: return "lzo";
    case Codec::Lz4: return "lz4";
    case Codec::Zstd: return "zstd";
  }
  return "unknown";
}

Codec parseCodec(const std::string& name) {
  for (uint8_t i = 0; i < kCodecCount; ++i) {
    if (name == codecName(static_cast<Codec>(i))) return static_cast<Codec>(i);
  }
  throw std::invalid_argument("unknown codec '" + name + "' (expected none, lzo, lz4 or zstd)");
}

void compressAppend(Codec c, std::span<const std::byte> raw, std::vector<std::byte>& out) {
  if (c == Codec::None) return (void)out.insert(out.end(), raw.begin(), raw.end());
  // Encoded into a buffer kept per thread, then appended: growing `out` to the codec's bound
  // would zero-fill (and fault in) ~the raw size per message only to shrink it to ~1/4
  // (a renderer's pieces: ~3% of a 4-renderer farm's CPU).
  thread_local std::vector<unsigned char> scratch;
  if (c == Codec::Lz4 && raw.size() > LZ4_MAX_INPUT_SIZE) throw std::length_error("lz4: input larger than 2 GB");
  const size_t cap = bound(c, raw.size());
  if (scratch.size() < cap) scratch.resize(cap);
  size_t n = 0;
  switch (c) {
    case Codec::None: break;
    case Codec::Lzo: n = compressLzo(raw, scratch.data()); break;
    case Codec::Lz4: n = compressLz4(raw, scratch.data(), cap); break;
    case Codec::Zstd: n = compressZstd(raw, scratch.data(), cap); break;
  }
  const auto* p = reinterpret_cast<const std::byte*>(scratch.data());
  out.insert(out.end(), p, p + n);
}

std::vector<std::byte> compress(Codec c, std::span<const std::byte> raw) {
  std::vector<std::byte> out;
  compressAppend(c, raw, out);
  return out;
}

Result<size_t> decompressInto(Codec c, std::span<const std::byte> encoded, std::span<std::byte> out) {
  const size_t want = out.size();
  switch (c) {
    case Codec::None:
      if (encoded.size() != want) return Result<size_t>::fail(sizeMismatch("none", encoded.size(), want));
      if (want) std::memcpy(out.data(), encoded.data(), want);
      return want;
    case Codec::Lzo: {
      initLzoOnce();
      lzo_uint got = want;
      int rc = lzo1x_decompress_safe(bytesOf(encoded), encoded.size(), bytesOf(out), &got, nullptr);
      if (rc != LZO_E_OK) return Result<size_t>::fail("lzo: corrupt data (error " + std::to_string(rc) + ")");
      if (got != want) return Result<size_t>::fail(sizeMismatch("lzo", got, want));
      return want;
    }
    case Codec::Lz4: {
      if (encoded.size() > INT_MAX || want > INT_MAX) return Result<size_t>::fail("lz4: sizes exceed 2 GB");
      int got = LZ4_decompress_safe(reinterpret_cast<const char*>(bytesOf(encoded)),
                                    reinterpret_cast<char*>(bytesOf(out)), static_cast<int>(encoded.size()),
                                    static_cast<int>(want));
      if (got < 0) return Result<size_t>::fail("lz4: corrupt data");
      if (static_cast<size_t>(got) != want) return Result<size_t>::fail(sizeMismatch("lz4", got, want));
      return want;
    }
    case Codec::Zstd: {
      unsigned long long declared = ZSTD_getFrameContentSize(bytesOf(encoded), encoded.size());
      if (declared == ZSTD_CONTENTSIZE_ERROR) return Result<size_t>::fail("zstd: not a zstd frame");
      if (declared != want) {
        return Result<size_t>::fail(declared == ZSTD_CONTENTSIZE_UNKNOWN
                                        ? std::string("zstd: frame content size missing")
                                        : sizeMismatch("zstd frame", declared, want));
      }
      static thread_local std::unique_ptr<ZSTD_DCtx, ZstdDeleter> ctx(ZSTD_createDCtx());
      size_t got = ZSTD_decompressDCtx(ctx.get(), bytesOf(out), want, bytesOf(encoded), encoded.size());
      if (ZSTD_isError(got)) return Result<size_t>::fail(std::string("zstd: ") + ZSTD_getErrorName(got));
      if (got != want) return Result<size_t>::fail(sizeMismatch("zstd", got, want));
      return want;
    }
  }
  return Result<size_t>::fail("unknown codec " + std::to_string(static_cast<int>(c)));
}

bool plausibleRawSize(Codec c, std::span<const std::byte> encoded, size_t raw_size) {
  const size_t n = encoded.size();
  switch (c) {
    case Codec::None: return n == raw_size;
    // One byte of an LZ4 or LZO1X length extension adds at most 255 output bytes: both
    // top out near 255:1 (measured: 255.0 and 225.5 on 64 MiB of zeros).
    case Codec::Lzo:
    case Codec::Lz4: return raw_size / 256 <= n;
    case Codec::Zstd: {
      // An RLE block is 4 bytes for at most 128 KiB; the frame header states the size.
      if (raw_size / 32768 > n) return false;
      return ZSTD_getFrameContentSize(bytesOf(encoded), n) == raw_size;
    }
  }
  return false;
}

Result<std::vector<std::byte>> decompress(Codec c, std::span<const std::byte> encoded, size_t raw_size) {
  using R = Result<std::vector<std::byte>>;
  if (static_cast<uint8_t>(c) >= kCodecCount) return R::fail("unknown codec " + std::to_string(static_cast<int>(c)));
  // Fail before allocating raw_size when the answer is already known.
  if (!plausibleRawSize(c, encoded, raw_size)) {
    return R::fail(std::string(codecName(c)) + ": " + std::to_string(encoded.size()) + " bytes cannot decode to " +
                   std::to_string(raw_size));
  }
  std::vector<std::byte> out(raw_size);
  auto r = decompressInto(c, encoded, out);
  if (!r) return R::fail(r.error());
  return out;
}

}  // namespace tessera
