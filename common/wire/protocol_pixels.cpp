// Pixel messages on the wire: uncompressed metadata, then the pixels compressed with the
// message's codec. Decoding checks the metadata (and so the exact decoded size) before it
// allocates or decompresses anything.
#include <span>
#include <stdexcept>
#include <string>

#include "common/wire/protocol.h"
#include "common/wire/protocol_internal.h"
#include "common/wire/row_filter.h"
#include "common/wire/strips.h"

namespace tessera::proto {

using detail::ByteReader;
using detail::ByteWriter;

namespace {

// Finishes a pixel message whose metadata is already in msg.
void appendPixels(std::vector<std::byte>& msg, Type type, uint64_t frame, uint32_t sender, Codec codec,
                  std::span<const std::byte> pixels) {
  const size_t meta = msg.size() - kHeaderSize;
  compressAppend(codec, pixels, msg);
  detail::finishMessage(msg, type, frame, sender, codec, meta + pixels.size());
}

std::string tooLarge(const char* what, size_t bytes, size_t most) {
  return std::string(what) + ": " + std::to_string(bytes) + " pixel bytes, more than the " + std::to_string(most) +
         " this stage's frames can hold (refused before decoding)";
}

// The decoded size of the pixels that follow the metadata, or a failure.
Result<size_t> pixelBytes(const Header& h, const ByteReader& r) {
  if (h.raw_size < r.pos()) {
    return Result<size_t>::fail("raw_size " + std::to_string(h.raw_size) + " smaller than the metadata");
  }
  return h.raw_size - r.pos();
}

// A piece's pixels travel Up-filtered (row_filter.h): rows of the active rect, in its
// format's planes (rgba16f: the low-byte plane, then the high-byte plane).
size_t piecePlanes(PixelFormat f) { return f == PixelFormat::RGBA16F ? 2 : 1; }
size_t pieceRowBytes(const Piece& m) {
  return static_cast<size_t>(m.active.w) * bytesPerPixel(m.format) / piecePlanes(m.format);
}

}  // namespace

std::vector<std::byte> encode(const Piece& m, uint32_t sender, Codec codec) {
  const size_t want = static_cast<size_t>(m.active.area()) * bytesPerPixel(m.format);
  if (m.pixels.size() != want) {
    throw std::invalid_argument("encode Piece: " + std::to_string(m.pixels.size()) + " pixel bytes for active " +
                                detail::rectText(m.active) + " (expected " + std::to_string(want) + ")");
  }
  auto msg = detail::beginMessage();
  ByteWriter w(msg);
  w.u32(m.epoch);
  w.u32(m.renderer);
  w.u32(m.brick);
  detail::writeRect(w, m.region);
  detail::writeRect(w, m.active);
  w.u8(static_cast<uint8_t>(m.format));
  w.f64(m.render_ms);
  w.f64(m.encode_ms);
  // Kept per thread: a fresh buffer of a piece's size costs more in page faults (~2.5 ms
  // for 3.4 MB) than the filter itself (~0.5 ms).
  thread_local std::vector<std::byte> filtered;
  filtered.resize(m.pixels.size());
  upFilter(m.pixels, filtered, pieceRowBytes(m), piecePlanes(m.format));
  appendPixels(msg, Type::Piece, m.frame, sender, codec, filtered);
  return msg;
}

Result<Piece> decodePiece(std::span<const std::byte> msg, size_t max_bytes) {
  using R = Result<Piece>;
  auto o = detail::openMessage(msg, Type::Piece, true);
  if (!o) return R::fail(o.error());
  ByteReader r(o->payload);
  Piece m;
  m.frame = o->header.frame;
  m.epoch = r.u32("epoch");
  m.renderer = r.u32("renderer");
  m.brick = r.u32("brick");
  m.region = detail::readRect(r, "region");
  m.active = detail::readRect(r, "active");
  uint8_t format = r.u8("format");
  m.render_ms = detail::readFinite(r, "render_ms");
  m.encode_ms = detail::readFinite(r, "encode_ms");
  if (r.ok() && !validPixelFormat(format)) r.fail("format " + std::to_string(format) + " unknown");
  m.format = static_cast<PixelFormat>(format);
  detail::checkSaneRect(r, m.region, "region");
  detail::checkSaneRect(r, m.active, "active");
  if (r.ok() && !m.active.empty() &&
      (m.active.x < m.region.x || m.active.y < m.region.y || m.active.x + m.active.w > m.region.x + m.region.w ||
       m.active.y + m.active.h > m.region.y + m.region.h)) {
    r.fail("active " + detail::rectText(m.active) + " outside region " + detail::rectText(m.region));
  }
  if (!r.ok()) return R::fail("Piece: " + r.error());
  auto bytes = pixelBytes(o->header, r);
  if (!bytes) return R::fail("Piece: " + bytes.error());
  const size_t want = static_cast<size_t>(m.active.area()) * bytesPerPixel(m.format);
  if (*bytes != want) {
    return R::fail("Piece: " + std::to_string(*bytes) + " pixel bytes for active " + detail::rectText(m.active) +
                   " (expected " + std::to_string(want) + ")");
  }
  if (want > max_bytes) return R::fail(tooLarge("Piece", want, max_bytes));
  if (!plausibleRawSize(o->header.codec, r.rest(), want)) {
    return R::fail("Piece: " + std::to_string(r.remaining()) + " " + codecName(o->header.codec) +
                   " bytes cannot hold " + std::to_string(want) + " pixel bytes");
  }
  m.pixels.resize(want);
  auto d = decompressInto(o->header.codec, r.rest(), m.pixels);
  if (!d) return R::fail("Piece: pixels: " + d.error());
  upUnfilter(m.pixels, pieceRowBytes(m), piecePlanes(m.format));
  return m;
}

std::vector<std::byte> encode(const Strips& m, uint32_t sender, Codec codec) {
  auto msg = detail::beginMessage();
  ByteWriter w(msg);
  w.u32(m.epoch);
  w.u32(m.sender);
  w.f64(m.composite_ms);
  w.f64(m.encode_ms);
  w.f64(m.render_ms);
  w.u64(m.active_pixels);
  // Strips of one width travel strip-filtered (row_filter.h) for the codec; any other stream,
  // or any stream without a codec, as it is.
  const auto stream = std::as_bytes(std::span(m.stream));
  const size_t strip_bytes = codec == Codec::None ? 0 : uniformStripBytes(m.stream);
  w.u32(static_cast<uint32_t>(strip_bytes));
  if (!strip_bytes) {
    appendPixels(msg, Type::Strips, m.frame, sender, codec, stream);
    return msg;
  }
  thread_local std::vector<std::byte> filtered;
  filtered.resize(stream.size());
  stripFilter(stream, filtered, strip_bytes);
  appendPixels(msg, Type::Strips, m.frame, sender, codec, filtered);
  return msg;
}

Result<Strips> decodeStrips(std::span<const std::byte> msg, size_t max_bytes) {
  using R = Result<Strips>;
  auto o = detail::openMessage(msg, Type::Strips, true);
  if (!o) return R::fail(o.error());
  ByteReader r(o->payload);
  Strips m;
  m.frame = o->header.frame;
  m.epoch = r.u32("epoch");
  m.sender = r.u32("sender");
  m.composite_ms = detail::readFinite(r, "composite_ms");
  m.encode_ms = detail::readFinite(r, "encode_ms");
  m.render_ms = detail::readFinite(r, "render_ms");
  m.active_pixels = r.u64("active_pixels");
  const uint32_t strip_bytes = r.u32("strip_bytes");
  if (!r.ok()) return R::fail("Strips: " + r.error());
  auto bytes = pixelBytes(o->header, r);
  if (!bytes) return R::fail("Strips: " + bytes.error());
  // A strip is a header and at most 65535 pixels (its 16-bit width); the stream holds at least one.
  if (strip_bytes && (strip_bytes <= 8 || (strip_bytes - 8) % 4 != 0 || strip_bytes > 8 + 4 * 65535u ||
                      *bytes < strip_bytes || *bytes % strip_bytes != 0)) {
    return R::fail("Strips: strip_bytes " + std::to_string(strip_bytes) + " does not divide a " +
                   std::to_string(*bytes) + "-byte stream into strips of a header and whole rgba8 pixels");
  }
  if (*bytes > max_bytes) return R::fail(tooLarge("Strips", *bytes, max_bytes));
  if (!plausibleRawSize(o->header.codec, r.rest(), *bytes)) {
    return R::fail("Strips: " + std::to_string(r.remaining()) + " " + codecName(o->header.codec) +
                   " bytes cannot hold a " + std::to_string(*bytes) + "-byte stream");
  }
  m.stream.resize(*bytes);
  auto d = decompressInto(o->header.codec, r.rest(), std::as_writable_bytes(std::span(m.stream)));
  if (!d) return R::fail("Strips: stream: " + d.error());
  if (strip_bytes) stripUnfilter(std::as_writable_bytes(std::span(m.stream)), strip_bytes);
  return m;
}

std::vector<std::byte> encode(const Framebuffer& m, uint32_t sender, Codec codec) {
  if (m.width < 0 || m.height < 0 || m.pixels.size() != (size_t)m.width * m.height * 4)
    throw std::invalid_argument("encode Framebuffer: " + std::to_string(m.pixels.size()) + " bytes for " +
                                std::to_string(m.width) + "x" + std::to_string(m.height));
  auto msg = detail::beginMessage();
  ByteWriter w(msg);
  w.u32(m.epoch);
  w.u32(m.renderer);
  w.i32(m.width);
  w.i32(m.height);
  w.f64(m.render_ms);
  appendPixels(msg, Type::Framebuffer, m.frame, sender, codec, m.pixels);
  return msg;
}

Result<Framebuffer> decodeFramebuffer(std::span<const std::byte> msg, size_t max_bytes) {
  using R = Result<Framebuffer>;
  auto o = detail::openMessage(msg, Type::Framebuffer, true);
  if (!o) return R::fail(o.error());
  ByteReader r(o->payload);
  Framebuffer m;
  m.frame = o->header.frame;
  m.epoch = r.u32("epoch");
  m.renderer = r.u32("renderer");
  m.width = r.i32("width");
  m.height = r.i32("height");
  m.render_ms = detail::readFinite(r, "render_ms");
  // A framebuffer packs tiles of at most the image's size side by side: twice the largest
  // image edge bounds it generously.
  if (r.ok() && (m.width < 0 || m.height < 0 || m.width > 2 * detail::kMaxDimension || m.height > 2 * detail::kMaxDimension))
    r.fail("size " + std::to_string(m.width) + "x" + std::to_string(m.height) + " out of range");
  if (!r.ok()) return R::fail("Framebuffer: " + r.error());
  auto bytes = pixelBytes(o->header, r);
  if (!bytes) return R::fail("Framebuffer: " + bytes.error());
  const size_t want = (size_t)m.width * m.height * 4;
  if (*bytes != want)
    return R::fail("Framebuffer: " + std::to_string(*bytes) + " pixel bytes for " + std::to_string(m.width) + "x" +
                   std::to_string(m.height));
  if (want > max_bytes) return R::fail(tooLarge("Framebuffer", want, max_bytes));
  if (!plausibleRawSize(o->header.codec, r.rest(), want))
    return R::fail("Framebuffer: " + std::to_string(r.remaining()) + " bytes cannot hold " + std::to_string(want));
  m.pixels.resize(want);
  auto d = decompressInto(o->header.codec, r.rest(), m.pixels);
  if (!d) return R::fail("Framebuffer: pixels: " + d.error());
  return m;
}

}  // namespace tessera::proto
