// The wire protocol: header framing and the per-frame reports (Stats, FrameDone, Input).
// Membership messages live in protocol_membership.cpp, FrameParams in
// protocol_frame_params.cpp, pixel messages (Piece, Strips) in protocol_pixels.cpp.
#include "common/wire/protocol.h"

#include <libdeflate.h>

#include <cstdio>
#include <stdexcept>

#include "common/wire/protocol_internal.h"

namespace tessera::proto {
namespace detail {

namespace {
// libdeflate's: vectorized, ~15x liblzo2's (every piece is summed twice, by its sender and
// its receiver: ~1% of a 4-renderer farm's CPU with liblzo2's).
uint32_t adler32(std::span<const std::byte> p) { return libdeflate_adler32(1, p.data(), p.size()); }
}  // namespace

std::vector<std::byte> beginMessage() {
  std::vector<std::byte> msg(kHeaderSize);
  return msg;
}

void finishMessage(std::vector<std::byte>& msg, Type type, uint64_t frame, uint32_t sender, Codec codec,
                   size_t raw_size) {
  const size_t encoded = msg.size() - kHeaderSize;
  if (raw_size > kMaxPayload || encoded > kMaxPayload) {
    throw std::length_error(std::string(typeName(type)) + ": payload of " + std::to_string(raw_size) +
                            " bytes exceeds kMaxPayload");
  }
  std::vector<std::byte> h;
  h.reserve(kHeaderSize);
  ByteWriter w(h);
  w.u32(kMagic);
  w.u16(kVersion);
  w.u16(static_cast<uint16_t>(type));
  w.u64(frame);
  w.u32(sender);
  w.u8(static_cast<uint8_t>(codec));
  w.u8(0);   // flags
  w.u16(0);  // reserved
  w.u32(static_cast<uint32_t>(raw_size));
  w.u32(static_cast<uint32_t>(encoded));
  w.u32(adler32(std::span(msg).subspan(kHeaderSize)));
  std::copy(h.begin(), h.end(), msg.begin());
}

Result<Opened> openMessage(std::span<const std::byte> msg, Type expected, bool pixels) {
  auto h = decodeHeader(msg);
  if (!h) return Result<Opened>::fail(h.error());
  if (h->type != expected) {
    return Result<Opened>::fail(std::string(typeName(expected)) + ": message is a " + typeName(h->type));
  }
  if (!pixels && h->codec != Codec::None) {
    return Result<Opened>::fail(std::string(typeName(expected)) + ": codec " + codecName(h->codec) + " != none");
  }
  return Opened{*h, msg.subspan(kHeaderSize)};
}

void writeRect(ByteWriter& w, const Rect& r) {
  w.i32(r.x);
  w.i32(r.y);
  w.i32(r.w);
  w.i32(r.h);
}

Rect readRect(ByteReader& r, const char* field) {
  Rect out;
  out.x = r.i32(field);
  out.y = r.i32(field);
  out.w = r.i32(field);
  out.h = r.i32(field);
  return out;
}

std::string rectText(const Rect& r) {
  return std::to_string(r.x) + "," + std::to_string(r.y) + " " + std::to_string(r.w) + "x" + std::to_string(r.h);
}

void checkSaneRect(ByteReader& r, const Rect& rect, const char* field) {
  if (!r.ok()) return;
  auto in = [](int v) { return v >= 0 && v <= kMaxDimension; };
  if (!in(rect.x) || !in(rect.y) || !in(rect.w) || !in(rect.h) || rect.x + rect.w > kMaxDimension ||
      rect.y + rect.h > kMaxDimension) {
    r.fail(std::string(field) + " " + rectText(rect) + " out of range");
  }
}

double readFinite(ByteReader& r, const char* field) {
  double v = r.f64(field);
  if (r.ok() && !std::isfinite(v)) r.fail(std::string(field) + " not finite");
  return v;
}

}  // namespace detail

using detail::ByteReader;
using detail::ByteWriter;

const char* typeName(Type t) {
  switch (t) {
    case Type::Hello: return "Hello";
    case Type::Welcome: return "Welcome";
    case Type::FrameParams: return "FrameParams";
    case Type::Piece: return "Piece";
    case Type::Strips: return "Strips";
    case Type::FrameDone: return "FrameDone";
    case Type::Heartbeat: return "Heartbeat";
    case Type::Input: return "Input";
    case Type::Stats: return "Stats";
    case Type::Shutdown: return "Shutdown";
    case Type::Framebuffer: return "Framebuffer";
    case Type::Roster: return "Roster";
    case Type::Probe: return "Probe";
  }
  return "unknown";
}

size_t bytesPerPixel(PixelFormat f) {
  switch (f) {
    case PixelFormat::RGBA8: return 4;
    case PixelFormat::RGBA16F: return 8;
    case PixelFormat::RGBA32F: return 16;
  }
  return 0;
}

Result<Header> decodeHeader(std::span<const std::byte> msg) {
  using R = Result<Header>;
  if (msg.size() < kHeaderSize) {
    return R::fail("header: truncated, " + std::to_string(msg.size()) + " < " + std::to_string(kHeaderSize) + " bytes");
  }
  ByteReader r(msg.first(kHeaderSize));
  Header h;
  uint32_t magic = r.u32("magic");
  h.version = r.u16("version");
  uint16_t type = r.u16("type");
  h.frame = r.u64("frame");
  h.sender = r.u32("sender");
  uint8_t codec = r.u8("codec");
  uint8_t flags = r.u8("flags");
  uint16_t reserved = r.u16("reserved");
  h.raw_size = r.u32("raw_size");
  h.encoded_size = r.u32("encoded_size");
  h.checksum = r.u32("checksum");
  if (magic != kMagic) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "header: magic 0x%08x != 0x%08x", magic, kMagic);
    return R::fail(buf);
  }
  if (h.version != kVersion) {
    return R::fail("header: version " + std::to_string(h.version) + " != " + std::to_string(kVersion));
  }
  if (type < 1 || type > kTypeCount) return R::fail("header: type " + std::to_string(type) + " unknown");
  h.type = static_cast<Type>(type);
  if (codec >= kCodecCount) return R::fail("header: codec " + std::to_string(codec) + " unknown");
  h.codec = static_cast<Codec>(codec);
  if (flags != 0 || reserved != 0) return R::fail("header: flags/reserved not zero");
  const size_t actual = msg.size() - kHeaderSize;
  if (h.encoded_size != actual) {
    return R::fail("header: encoded_size " + std::to_string(h.encoded_size) + " != " + std::to_string(actual) +
                   " payload bytes");
  }
  if (h.raw_size > kMaxPayload) return R::fail("header: raw_size " + std::to_string(h.raw_size) + " oversized");
  if (h.encoded_size > kMaxPayload) return R::fail("header: encoded_size oversized");
  if (detail::adler32(msg.subspan(kHeaderSize)) != h.checksum) return R::fail("header: checksum mismatch");
  if (h.codec == Codec::None && h.raw_size != h.encoded_size) {
    return R::fail("header: codec none but raw_size " + std::to_string(h.raw_size) + " != encoded_size");
  }
  return h;
}

using detail::decodeStructured;
using detail::encodeStructured;
using detail::readRole;

// ---- per-frame reports ----------------------------------------------------------------
std::vector<std::byte> encode(const StageStats& m, uint32_t sender) {
  return encodeStructured(Type::Stats, m.frame, sender, [&](ByteWriter& w) {
    w.u8(static_cast<uint8_t>(m.role));
    w.u32(m.rank);
    w.u32(m.epoch);
    w.f64(m.work_ms);
    w.f64(m.encode_ms);
    w.f64(m.decode_ms);
    w.u64(m.bytes_raw);
    w.u64(m.bytes_encoded);
    w.u64(m.active_pixels);
    detail::writeRect(w, m.active);
    w.u64(m.dropped);
    w.u32(static_cast<uint32_t>(m.tile_ms.size()));
    for (double t : m.tile_ms) w.f64(t);
    w.u64(m.chunks_drawn);
    w.u64(m.chunks_total);
    w.u64(m.triangles);
    w.u32(m.images_made);
    w.u32(m.images_reused);
    w.f64(m.load_ms);
    w.u32(m.step);
    w.u32(m.step_hits);
    w.u32(m.step_misses);
    w.u64(m.bytes_read);
    w.f64(m.prefetch_ms);
    w.f64(m.wait_ms);
  });
}
Result<StageStats> decodeStageStats(std::span<const std::byte> msg) {
  return decodeStructured<StageStats>(msg, Type::Stats, [](ByteReader& r, const Header& h, StageStats& m) {
    m.frame = h.frame;
    m.role = readRole(r);
    m.rank = r.u32("rank");
    m.epoch = r.u32("epoch");
    m.work_ms = detail::readFinite(r, "work_ms");
    m.encode_ms = detail::readFinite(r, "encode_ms");
    m.decode_ms = detail::readFinite(r, "decode_ms");
    m.bytes_raw = r.u64("bytes_raw");
    m.bytes_encoded = r.u64("bytes_encoded");
    m.active_pixels = r.u64("active_pixels");
    m.active = detail::readRect(r, "active");
    detail::checkSaneRect(r, m.active, "active");
    m.dropped = r.u64("dropped");
    m.tile_ms.resize(r.count("tile_ms", 1u << 20, 8));
    for (double& t : m.tile_ms) t = detail::readFinite(r, "tile_ms");
    m.chunks_drawn = r.u64("chunks_drawn");
    m.chunks_total = r.u64("chunks_total");
    m.triangles = r.u64("triangles");
    m.images_made = r.u32("images_made");
    m.images_reused = r.u32("images_reused");
    m.load_ms = detail::readFinite(r, "load_ms");
    m.step = r.u32("step");
    m.step_hits = r.u32("step_hits");
    m.step_misses = r.u32("step_misses");
    m.bytes_read = r.u64("bytes_read");
    m.prefetch_ms = detail::readFinite(r, "prefetch_ms");
    m.wait_ms = detail::readFinite(r, "wait_ms");
  });
}

std::vector<std::byte> encode(const FrameDone& m, uint32_t sender) {
  return encodeStructured(Type::FrameDone, m.frame, sender, [&](ByteWriter& w) {
    w.f64(m.display_ms);
    w.f64(m.route_ms);
    w.u64(m.bytes_encoded);
    w.u64(m.strips_rejected);
    w.u64(m.dropped);
    w.f64(m.input_ms);
  });
}
Result<FrameDone> decodeFrameDone(std::span<const std::byte> msg) {
  return decodeStructured<FrameDone>(msg, Type::FrameDone, [](ByteReader& r, const Header& h, FrameDone& m) {
    m.frame = h.frame;
    m.display_ms = detail::readFinite(r, "display_ms");
    m.route_ms = detail::readFinite(r, "route_ms");
    m.bytes_encoded = r.u64("bytes_encoded");
    m.strips_rejected = r.u64("strips_rejected");
    m.dropped = r.u64("dropped");
    m.input_ms = detail::readFinite(r, "input_ms");
    if (r.ok() && m.input_ms < 0) r.fail("input_ms " + std::to_string(m.input_ms) + " negative");
  });
}

std::vector<std::byte> encode(const Input& m, uint32_t sender) {
  return encodeStructured(Type::Input, 0, sender, [&](ByteWriter& w) {
    w.u64(m.seq);
    w.f64(m.orbit_dx);
    w.f64(m.orbit_dy);
    w.f64(m.zoom);
    w.u8(m.quality ? static_cast<uint8_t>(*m.quality) : 0);
    w.boolean(m.interacting);
    w.i32(m.width);
    w.i32(m.height);
    w.u8(static_cast<uint8_t>(m.time));
    w.boolean(m.home);
    w.f64(m.window_shift);
    w.f64(m.window_scale);
  });
}
Result<Input> decodeInput(std::span<const std::byte> msg) {
  return decodeStructured<Input>(msg, Type::Input, [](ByteReader& r, const Header&, Input& m) {
    m.seq = r.u64("seq");
    m.orbit_dx = detail::readFinite(r, "orbit_dx");
    m.orbit_dy = detail::readFinite(r, "orbit_dy");
    m.zoom = detail::readFinite(r, "zoom");
    if (r.ok() && m.zoom <= 0) r.fail("zoom " + std::to_string(m.zoom) + " not positive");
    // 0: unchanged; else a named preset (a display cannot ask for a custom quality).
    const uint8_t q = r.u8("quality");
    if (r.ok() && q > static_cast<uint8_t>(QualityName::Fast))
      r.fail("quality " + std::to_string(q) + " not in 0..3 (unchanged, reference, default, fast)");
    if (q != 0) m.quality = static_cast<QualityName>(q);
    m.interacting = r.boolean("interacting");
    m.width = r.i32("width");
    m.height = r.i32("height");
    const bool unchanged = m.width == 0 && m.height == 0;
    if (r.ok() && !unchanged && (m.width < 1 || m.width > detail::kMaxDimension || m.height < 1 || m.height > detail::kMaxDimension))
      r.fail("window size " + std::to_string(m.width) + "x" + std::to_string(m.height) + " neither 0x0 nor within 1..16384");
    const uint8_t t = r.u8("time");
    if (r.ok() && t > static_cast<uint8_t>(TimeKey::LastKey)) r.fail("time key " + std::to_string(t) + " not in 0..5");
    m.time = static_cast<TimeKey>(t);
    m.home = r.boolean("home");
    m.window_shift = detail::readFinite(r, "window_shift");
    m.window_scale = detail::readFinite(r, "window_scale");
    if (r.ok() && m.window_scale <= 0) r.fail("window_scale " + std::to_string(m.window_scale) + " not positive");
  });
}

}  // namespace tessera::proto
