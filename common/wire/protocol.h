// The wire protocol: the one place that knows the byte layout of every message.
// Every message = 36-byte little-endian header + payload. Header fields:
//   magic u32 "TSER" | version u16 | type u16 | frame u64 | sender u32 |
//   codec u8 | flags u8 | reserved u16 | raw_size u32 | encoded_size u32 | checksum u32 (Adler-32 of payload)
// raw_size = payload size once decoded; encoded_size = bytes after the header. Pixel
// messages carry uncompressed metadata then the codec-compressed pixels; others use none.
// The header's frame field carries the `frame` of messages that have one.
// Structured payloads are explicit little-endian fields written by ByteWriter; never a
// memcpy'd struct. Decoders validate every field before touching memory and never throw.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/bricks.h"
#include "common/camera.h"
#include "common/wire/codec.h"
#include "common/image.h"
#include "common/result.h"
#include "common/scene.h"

namespace tessera::proto {

inline constexpr uint32_t kMagic = 0x52455354;  // bytes "TSER" on the wire
inline constexpr uint16_t kVersion = 1;
inline constexpr size_t kHeaderSize = 36;
inline constexpr uint32_t kMaxPayload = 256u << 20;  // larger is rejected as oversized

enum class Type : uint16_t {
  Hello = 1, Welcome, FrameParams, Piece, Strips, FrameDone, Heartbeat, Input, Stats, Shutdown, Framebuffer, Roster,
  Probe,
  Last = Probe  // keep last: the decoder's range check derives from it
};
inline constexpr uint16_t kTypeCount = static_cast<uint16_t>(Type::Last);
const char* typeName(Type t);

// Role and PixelFormat travel as u8; `Last` (keep it last) bounds the decoders' range checks.
enum class Role : uint8_t { Renderer = 1, Compositor = 2, Display = 3, Last = Display };
// RGBA16F pixels travel as two byte planes (low bytes of every half, then high bytes).
enum class PixelFormat : uint8_t { RGBA8 = 1, RGBA16F = 2, RGBA32F = 3, Last = RGBA32F };
constexpr bool validRole(uint8_t v) { return v >= 1 && v <= static_cast<uint8_t>(Role::Last); }
constexpr bool validPixelFormat(uint8_t v) { return v >= 1 && v <= static_cast<uint8_t>(PixelFormat::Last); }
size_t bytesPerPixel(PixelFormat f);

struct Header {
  uint16_t version = kVersion;
  Type type = Type::Hello;
  uint64_t frame = 0;
  uint32_t sender = 0;
  Codec codec = Codec::None;
  uint32_t raw_size = 0, encoded_size = 0, checksum = 0;
  bool operator==(const Header&) const = default;
};

// ---- messages ---------------------------------------------------------------------
struct Hello {                                                             // stage -> master
  Role role = Role::Renderer; uint32_t pid = 0; std::string endpoint;
  bool operator==(const Hello&) const = default;
};
struct Welcome {                                                           // master -> stage
  Role role = Role::Renderer; uint32_t rank = 0;
  bool operator==(const Welcome&) const = default;
};
struct Heartbeat {                                                         // stage -> master
  Role role = Role::Renderer; uint32_t rank = 0;
  bool operator==(const Heartbeat&) const = default;
};
// Who may send on a stage's data socket: the data-connection routing ids of the members
// (16 random bytes + 'd', see StageLink), sent privately over each stage's control
// connection, never on the PUB socket, so a peer that did not join cannot learn them.
struct RosterEntry {
  Role role = Role::Renderer; uint32_t rank = 0; std::string identity;
  bool operator==(const RosterEntry&) const = default;
};
struct Roster {                                                            // master -> compositor, display
  uint32_t epoch = 0;
  std::vector<RosterEntry> members;
  bool operator==(const Roster&) const = default;
};
// The master's membership probe on PUB: a stage that receives anything on SUB knows its
// subscription is live and may say Hello. Carries nothing; stages skip it after joining.
struct Probe {                                                             // master -> all (PUB)
  bool operator==(const Probe&) const = default;
};
struct Shutdown {                                                          // master -> all
  std::string reason;
  bool operator==(const Shutdown&) const = default;
};

struct BrickAssignment {
  uint32_t renderer = 0; BrickBox brick;
  bool operator==(const BrickAssignment&) const = default;
};
// Sort-first: one screen tile drawn by `renderer`, routed by `compositor`.
struct TileAssignment {
  uint32_t renderer = 0, compositor = 0;
  Rect tile;
  bool operator==(const TileAssignment&) const = default;
};
struct CompositorRegion {
  uint32_t compositor = 0; Rect region; std::string endpoint;
  bool operator==(const CompositorRegion&) const = default;
};
struct FrameParams {                                                       // master -> all (PUB)
  uint64_t frame = 0;
  uint32_t epoch = 0;                        // bumped when membership changes; stale work is dropped
  Camera camera;
  Quality quality;
  int width = 0, height = 0;
  Codec codec = Codec::Lzo;                  // for pieces and strips
  PixelFormat format = PixelFormat::RGBA8;   // of pieces
  std::vector<BrickAssignment> bricks;       // one per renderer that has work
  std::vector<int> order;                    // brick indices (into `bricks`) front to back
  std::vector<CompositorRegion> regions;     // sort-last: tile the image; sort-first: each router's tiles' bounds
  std::vector<TileAssignment> tiles;         // sort-first (geometry) frames; empty for sort-last
  std::string display_endpoint;
  bool operator==(const FrameParams&) const = default;
};

struct Piece {                                 // renderer -> compositor
  uint64_t frame = 0;
  uint32_t epoch = 0;                          // FrameParams::epoch it was rendered for
  uint32_t renderer = 0, brick = 0;            // brick = index into FrameParams::bricks
  Rect region;                                 // the compositor's region (for validation)
  Rect active;                                 // sub-rect of region carried; empty => no pixels
  PixelFormat format = PixelFormat::RGBA8;
  std::vector<std::byte> pixels;               // raw (decoded) pixels of `active`, rows top to bottom
  double render_ms = 0, encode_ms = 0;
  bool operator==(const Piece&) const = default;
};

struct Strips {                                // compositor -> display
  uint64_t frame = 0;
  uint32_t epoch = 0;
  uint32_t compositor = 0;
  std::vector<uint8_t> stream;                 // raw (decoded) strip stream, see strips.h
  double composite_ms = 0, encode_ms = 0;
  double render_ms = 0;                        // slowest piece's render time (for the status line)
  uint64_t active_pixels = 0;
  bool operator==(const Strips&) const = default;
};

// Sort-first: a renderer's tiles packed left to right, top to bottom in one rgba8
// framebuffer, each tile row preceded by its two-pixel strip header (strips.h).
struct Framebuffer {                           // renderer -> compositor (router)
  uint64_t frame = 0;
  uint32_t epoch = 0, renderer = 0;
  int width = 0, height = 0;
  std::vector<std::byte> pixels;               // width*height*4, raw (decoded)
  double render_ms = 0;
  bool operator==(const Framebuffer&) const = default;
};

struct StageStats {                            // renderer/compositor -> master, per frame
  Role role = Role::Renderer; uint32_t rank = 0; uint64_t frame = 0;
  double work_ms = 0, encode_ms = 0;
  uint64_t bytes_raw = 0, bytes_encoded = 0, active_pixels = 0;
  Rect active;                                 // renderer: active region of its brick image
  uint64_t dropped = 0;                        // messages dropped so far (cumulative)
  // Sort-first renderers: ms per assigned tile (in FrameParams::tiles order), chunk-tile
  // pairs drawn, the mesh's chunk count and the triangles drawn.
  std::vector<double> tile_ms;
  uint64_t chunks_drawn = 0, chunks_total = 0, triangles = 0;
  bool operator==(const StageStats&) const = default;
};

struct FrameDone {                             // display -> master
  uint64_t frame = 0;
  double display_ms = 0, route_ms = 0;
  uint64_t bytes_encoded = 0, strips_rejected = 0, dropped = 0;
  bool operator==(const FrameDone&) const = default;
};

struct Input {                                 // display -> master (interactive camera)
  double orbit_dx = 0, orbit_dy = 0;           // degrees
  double zoom = 1;                             // multiply eye distance
  std::string quality;                         // "" = unchanged
  bool operator==(const Input&) const = default;
};

// ---- encode: header + payload; pixel payloads are compressed with `codec` -----------
std::vector<std::byte> encode(const Hello&, uint32_t sender);
std::vector<std::byte> encode(const Welcome&, uint32_t sender);
std::vector<std::byte> encode(const Heartbeat&, uint32_t sender);
std::vector<std::byte> encode(const Probe&, uint32_t sender);
std::vector<std::byte> encode(const Shutdown&, uint32_t sender);
std::vector<std::byte> encode(const Roster&, uint32_t sender);
std::vector<std::byte> encode(const FrameParams&, uint32_t sender);
std::vector<std::byte> encode(const Piece&, uint32_t sender, Codec codec);
std::vector<std::byte> encode(const Strips&, uint32_t sender, Codec codec);
std::vector<std::byte> encode(const Framebuffer&, uint32_t sender, Codec codec);
std::vector<std::byte> encode(const StageStats&, uint32_t sender);
std::vector<std::byte> encode(const FrameDone&, uint32_t sender);
std::vector<std::byte> encode(const Input&, uint32_t sender);

// ---- decode: validate header (magic, version, type range, sizes, checksum) ----------
Result<Header> decodeHeader(std::span<const std::byte> msg);
Result<Hello> decodeHello(std::span<const std::byte> msg);
Result<Welcome> decodeWelcome(std::span<const std::byte> msg);
Result<Heartbeat> decodeHeartbeat(std::span<const std::byte> msg);
Result<Probe> decodeProbe(std::span<const std::byte> msg);
Result<Shutdown> decodeShutdown(std::span<const std::byte> msg);
Result<Roster> decodeRoster(std::span<const std::byte> msg);
Result<FrameParams> decodeFrameParams(std::span<const std::byte> msg);
Result<Piece> decodePiece(std::span<const std::byte> msg);     // checks active within region, pixel count
Result<Strips> decodeStrips(std::span<const std::byte> msg);
Result<Framebuffer> decodeFramebuffer(std::span<const std::byte> msg);
Result<StageStats> decodeStageStats(std::span<const std::byte> msg);
Result<FrameDone> decodeFrameDone(std::span<const std::byte> msg);
Result<Input> decodeInput(std::span<const std::byte> msg);

}  // namespace tessera::proto
