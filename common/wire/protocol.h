// The wire protocol: the one place that states the byte layout of every message.
// Every message = 36-byte header + payload, all little-endian. Header (decodeHeader):
//   magic         u32  4  == kMagic (bytes "TSER")
//   version       u16  2  == kVersion
//   type          u16  2  1..Type::Last
//   frame         u64  8  the `frame` of messages that have one, else 0 (not checked)
//   sender        u32  4  sender's rank; any (informational, never trusted)
//   codec         u8   1  < kCodecCount; structured messages must use none (0)
//   flags         u8   1  == 0
//   reserved      u16  2  == 0
//   raw_size      u32  4  payload size once decoded, <= kMaxPayload; == encoded_size if codec none
//   encoded_size  u32  4  == bytes after the header, <= kMaxPayload
//   checksum      u32  4  == Adler-32 of the payload bytes
// Payload tables below list field, type, bytes, range as the decoder enforces it, in wire
// order. Types: u8..u64, i32, f64 (IEEE double; "finite" = not NaN/inf); bool = u8 0|1;
// str = u32 n <= 65536 (kMaxString) then n bytes; rect = i32 x, y, w, h (16 bytes);
// "sane rect" = 0 <= x, y, w, h and x + w, y + h <= 16384. A u32 count precedes repeated
// entries and must fit (count * smallest entry <= bytes left). No range = any value.
// Structured messages must use every payload byte. Pixel messages carry uncompressed
// metadata then the codec-compressed pixels; their decoded size (raw_size - metadata)
// is fixed by the metadata and checked before anything is allocated or decompressed.
// Payloads are written field by field (ByteWriter), never as a memcpy'd struct.
// Decoders validate every field before touching memory and never throw.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "common/bricks.h"
#include "common/camera.h"
#include "common/wire/codec.h"
#include "common/wire/frame_work.h"
#include "common/image.h"
#include "common/result.h"
#include "common/quality.h"
#include "common/transfer_function.h"

namespace tessera::proto {

inline constexpr uint32_t kMagic = 0x52455354;  // bytes "TSER" on the wire
inline constexpr uint16_t kVersion = 17;  // 2: FrameParams' mode, Hello's run; 3: Stats' reuse and loads;
  // 4: interaction (Input seq/size, FrameParams cancel/input_seq, FrameDone input_ms); 5: time steps; 6: Stats
  // carry their FrameParams' epoch; 7: Piece pixels Up-filtered; 8: binary-swap plans in FrameParams; 9: swap
  // bands go to the display as Strips; 10: Strips strip-filtered, Heartbeats name the awaited swap partner;
  // 11: Stats' wait_ms; 12: Welcome's volume_range; 13: Shutdown's run; 14: Input's home;
  // 15: Hello's scene; 16: the colour window (Input's window_shift/scale, FrameParams' window);
  // 17: FrameParams' quality.jitter
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
const char* roleName(Role r);
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
// Hello:      role u8 1 (1..Role::Last) | pid u32 4 | endpoint str 4+n | run str 4+n | scene str 4+n
//             endpoint: a compositor's advertised host ("" = the base host); a renderer's
//             binary-swap socket as peers reach it ("" = none: direct send only)
//             run: the farm's identity (TESSERA_RUN); the master refuses any other
//             scene: the stage's sceneIdentity (YAML text); the master refuses any other than
//             its own, naming the first line that differs
// Welcome:    role u8 1 (1..Role::Last) | rank u32 4 | volume_range f64 2x8
//             volume_range: the range the master maps to 0..1 for a volume file (the scene's
//             `range`, else the whole file's min..max, step 0's for a series; a constant file's
//             value c as [c, c + 1]), so a renderer reads only its bricks, not the file once
//             more for it; {0, 0}: none (a generated volume). Finite, lo < hi.
// Heartbeat:  role u8 1 (1..Role::Last) | rank u32 4 | waiting_frame u64 8 | waiting_for u32 4
//             waiting_for: whose part of frame waiting_frame it awaits (a renderer: its swap partner's;
//             a compositor: a renderer's piece; the display: a sender's strips), or kNobody
struct Hello {                                                             // stage -> master
  Role role = Role::Renderer; uint32_t pid = 0; std::string endpoint; std::string run; std::string scene{};
  bool operator==(const Hello&) const = default;
};
struct Welcome {                                                           // master -> stage
  Role role = Role::Renderer; uint32_t rank = 0; std::array<double, 2> volume_range{0, 0};
  bool operator==(const Welcome&) const = default;
};
inline constexpr uint32_t kNobody = 0xFFFFFFFFu;
struct Heartbeat {                                                         // stage -> master
  Role role = Role::Renderer; uint32_t rank = 0;
  uint64_t waiting_frame = 0; uint32_t waiting_for = kNobody;
  bool operator==(const Heartbeat&) const = default;
};
// Who may send on a stage's data socket: the data-connection routing ids of the members
// (16 random bytes + 'd', see StageLink), sent privately over each stage's control
// connection, never on the PUB socket, so a peer that did not join cannot learn them.
// Roster:
//   epoch             u32  4
//   members           u32  4    count <= 65536, then per member (>= 9 bytes):
//   members.role      u8   1    1..Role::Last
//   members.rank      u32  4
//   members.identity  str  4+n  n in 1..255 (a ZeroMQ routing id)
struct RosterEntry {
  Role role = Role::Renderer; uint32_t rank = 0; std::string identity;
  bool operator==(const RosterEntry&) const = default;
};
struct Roster {                                                            // master -> every stage
  uint32_t epoch = 0;
  std::vector<RosterEntry> members;
  bool operator==(const Roster&) const = default;
};
// The master's membership probe on PUB: a stage that receives anything on SUB knows its
// subscription is live and may say Hello. Carries nothing; stages skip it after joining.
// Probe:      empty payload (0 bytes)
struct Probe {                                                             // master -> all (PUB)
  bool operator==(const Probe&) const = default;
};
// Shutdown:   reason str 4+n | run str 4+n
//             run: the master's TESSERA_RUN; a stage skips another run's Shutdown (a master that
//             used the same endpoint just before this farm's)
struct Shutdown {                                                          // master -> all
  std::string reason; std::string run;
  bool operator==(const Shutdown&) const = default;
};

// FrameParams (header frame = frame):
//   epoch                      u32      4
//   camera.eye/target/up       3x3 f64  72    finite
//   camera.fov                 f64      8     finite, in (0, 180)
//   camera.orthographic        bool     1
//   camera.height              f64      8     finite, > 0
//   quality.name               u8       1     QualityName 1..Last
//   quality.step               f64      8     finite, > 0
//   quality.early_termination  f64      8     finite
//   quality.skip_empty         bool     1
//   quality.reference          bool     1
//   quality.jitter             bool     1
//   width, height              i32 x2   8     1..16384 each
//   codec                      u8       1     < kCodecCount
//   format                     u8       1     1..PixelFormat::Last
//   first_wanted               u64      8     <= frame
//   input_seq                  u64      8
//   input_first                u64      8     <= input_seq
//   interactive                bool     1
//   step, next_step            u32 x2   8     each < 1000000
//   window.center, .width      f64 x2   16    finite, |center| <= 1e6, width in (0, 1e6]
//   regions                    u32      4     count <= 65536, then per region (>= 24 bytes):
//   regions.compositor         u32      4
//   regions.region             rect     16    0 <= x, y, w, h; inside width x height
//   regions.endpoint           str      4+n
//   display_endpoint           str      4+n
//   mode                       u8       1     FrameMode 1..Last; then the mode's work:
// sort-last (mode 1):
//   bricks                     u32      4     count <= 65536, then per brick (28 bytes):
//   bricks.renderer            u32      4
//   bricks.lo, bricks.hi       3x i32   24    per axis 0 <= lo < hi <= 65536
//   order                      u32      4     count == bricks count, then:
//   order[i]                   i32      4     together a permutation of 0..count-1
//   swap                       u32      4     count 0 (direct send) or == bricks count (any count:
//                                             radix-k, swap_plan.h), then per renderer (>= 9 bytes):
//   swap.renderer              u32      4     each renderer of `bricks` exactly once
//   swap.endpoint              str      4+n   n >= 1: where that renderer takes swap pieces
// sort-first (mode 2):
//   tiles                      u32      4     count <= 2^20, then per tile (24 bytes):
//   tiles.renderer, compositor u32 x2   8
//   tiles.tile                 rect     16    w, h > 0; 0 <= x, y; inside width x height
struct FrameParams {                                                       // master -> all (PUB)
  uint64_t frame = 0;
  uint32_t epoch = 0;                        // bumped when membership changes; stale work is dropped
  Camera camera;
  Quality quality;
  int width = 0, height = 0;
  Codec codec = Codec::Lzo;                  // for pieces and strips
  PixelFormat format = PixelFormat::RGBA8;   // of pieces
  std::vector<CompositorRegion> regions;     // sort-last: tile the image; sort-first: each router's tiles' bounds
  std::string display_endpoint;
  // Frames below this one are cancelled (an interaction made them stale): stages skip them,
  // drop their parts without counting them as faults, and the display never waits for them.
  uint64_t first_wanted = 0;
  uint64_t input_seq = 0;                    // the newest display Input this frame shows (0: none)
  // The first Input that changed the view since the frame issued before this one (0: none,
  // the frame is not a response to input): the display measures input-to-present from it.
  uint64_t input_first = 0;
  bool interactive = false;                  // a reduced frame while the camera moves (level of detail)
  uint32_t step = 0;                         // the time step of the volume shown (0 for a static volume)
  uint32_t next_step = 0;                    // the step the master expects to show next: renderers prefetch it
  ColorWindow window;                        // the colour map's window (the user's window/level)
  std::variant<SortLastWork, SortFirstWork> work;  // the mode: each stage dispatches on it once
  FrameMode mode() const { return work.index() == 0 ? FrameMode::SortLast : FrameMode::SortFirst; }
  const SortLastWork* sortLast() const { return std::get_if<SortLastWork>(&work); }    // null if sort-first
  const SortFirstWork* sortFirst() const { return std::get_if<SortFirstWork>(&work); }  // null if sort-last
  bool operator==(const FrameParams&) const = default;
};
std::set<uint32_t> renderersWithWork(const FrameParams& p);  // ranks named by its bricks or tiles

// Piece (pixel message, header frame = frame; 61 bytes of metadata). Also what renderers
// exchange in a binary swap: then `region` is the part of the image the receiver keeps
// this round (swap_plan.h), `brick` the sender's brick, and the format at least rgba16f.
//   epoch, renderer, brick  u32 x3  12
//   region                  rect    16  sane
//   active                  rect    16  sane; inside region unless empty (w or h <= 0)
//   format                  u8      1   1..PixelFormat::Last
//   render_ms, encode_ms    f64 x2  16  finite
//   pixels                  codec   rest  decodes to exactly active.w * active.h * bytesPerPixel(format),
//                                         Up-filtered by rows within each plane (row_filter.h)
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

// Strips (pixel message, header frame = frame; 44 bytes of metadata):
//   epoch, sender                       u32 x2  8    the sending stage's rank
//   composite_ms, encode_ms, render_ms  f64 x3  24   finite
//   active_pixels                       u64     8
//   strip_bytes                         u32     4    0: the stream as it is; else every strip's length,
//                                                    the stream strip-filtered (row_filter.h)
//   stream                              codec   rest decodes to raw_size - 44 bytes (parsed later, strips.h)
struct Strips {                                // compositor (or binary-swap renderer) -> display
  uint64_t frame = 0;
  uint32_t epoch = 0;
  uint32_t sender = 0;                         // a compositor's rank; a renderer's in a binary-swap frame
  std::vector<uint8_t> stream;                 // raw (decoded) strip stream, see strips.h
  double composite_ms = 0, encode_ms = 0;
  double render_ms = 0;                        // slowest piece's render time (for the status line)
  uint64_t active_pixels = 0;
  bool operator==(const Strips&) const = default;
};

// Sort-first: a renderer's tiles packed left to right, top to bottom in one rgba8
// framebuffer, each tile row preceded by its two-pixel strip header (strips.h).
// Framebuffer (pixel message, header frame = frame; 24 bytes of metadata):
//   epoch, renderer  u32 x2  8
//   width, height    i32 x2  8    0..32768 each (twice the largest image edge)
//   render_ms        f64     8    finite
//   pixels           codec   rest decodes to exactly width * height * 4
struct Framebuffer {                           // renderer -> compositor (router)
  uint64_t frame = 0;
  uint32_t epoch = 0, renderer = 0;
  int width = 0, height = 0;
  std::vector<std::byte> pixels;               // width*height*4, raw (decoded)
  double render_ms = 0;
  bool operator==(const Framebuffer&) const = default;
};

// StageStats (type Stats, header frame = frame):
//   role                                         u8      1   1..Role::Last
//   rank                                         u32     4
//   epoch                                        u32     4
//   work_ms, encode_ms, decode_ms                f64 x3  24  finite
//   bytes_raw, bytes_encoded, active_pixels      u64 x3  24
//   active                                       rect    16  sane
//   dropped                                      u64     8
//   tile_ms                                      u32     4   count <= 2^20, then:
//   tile_ms[i]                                   f64     8   finite
//   chunks_drawn, chunks_total, triangles        u64 x3  24
//   images_made, images_reused                   u32 x2  8
//   load_ms                                      f64     8   finite
//   step, step_hits, step_misses                 u32 x3  12
//   bytes_read                                   u64     8
//   prefetch_ms                                  f64     8   finite
//   wait_ms                                      f64     8   finite
struct StageStats {                            // renderer/compositor -> master, per frame
  Role role = Role::Renderer; uint32_t rank = 0; uint64_t frame = 0;
  uint32_t epoch = 0;  // of the FrameParams answered: a frame issued again waits for the new issue's
  // What the stage sends: its output before (raw) and after (encoded) the codec, the time
  // spent encoding it, and the time spent decoding what it received (compositors).
  double work_ms = 0, encode_ms = 0, decode_ms = 0;
  uint64_t bytes_raw = 0, bytes_encoded = 0, active_pixels = 0;
  Rect active;                                 // renderer: active region of its brick image
  uint64_t dropped = 0;                        // messages dropped so far (cumulative)
  // Sort-first renderers: ms per assigned tile (in FrameParams::tiles order), chunk-tile
  // pairs drawn, the mesh's chunk count and the triangles drawn.
  std::vector<double> tile_ms;
  uint64_t chunks_drawn = 0, chunks_total = 0, triangles = 0;
  // Renderers: images (bricks or tiles) rendered this frame, and images reused from an
  // earlier frame because nothing that shapes them (camera, quality, size, brick) changed.
  uint32_t images_made = 0, images_reused = 0;
  double load_ms = 0;  // renderers: reading (or generating) voxels on the render path (new bricks, a step not cached), or waiting for the prefetch of the step
  // Renderers of a time series: the step shown, whether its voxels were in the step cache
  // (hits, misses: cumulative), the file bytes read since the last Stats (loads and
  // prefetches) and the prefetch thread's time since then.
  uint32_t step = 0, step_hits = 0, step_misses = 0;
  uint64_t bytes_read = 0;
  double prefetch_ms = 0;
  // Binary-swap renderers: time sat idle in the frame's rounds, a partner's piece awaited
  // and no next frame to render meanwhile (a slow link, a slower partner, no frame issued).
  double wait_ms = 0;
  bool operator==(const StageStats&) const = default;
};

// FrameDone (header frame = frame):
//   display_ms, route_ms                     f64 x2  16  finite
//   bytes_encoded, strips_rejected, dropped  u64 x3  24
//   input_ms                                 f64     8   finite, >= 0
struct FrameDone {                             // display -> master
  uint64_t frame = 0;
  double display_ms = 0, route_ms = 0;
  // From FrameParams::input_first (its event reaching the display) to the frame on screen;
  // 0 when the frame answers no input.
  double input_ms = 0;
  uint64_t bytes_encoded = 0, strips_rejected = 0, dropped = 0;
  bool operator==(const FrameDone&) const = default;
};

// Input:
//   seq                 u64     8    any (the display numbers its inputs 1, 2, ...)
//   orbit_dx, orbit_dy  f64 x2  16   finite
//   zoom                f64     8    finite, > 0
//   quality             u8      1    0 = unchanged, else QualityName Reference..Fast
//   interacting         bool    1
//   width, height       i32 x2  8    both 0 (unchanged) or both 1..16384
//   time                u8      1    TimeKey 0..Last
//   home                bool    1    back to the scene's camera and colour window first (the window's r)
//   window_shift        f64     8    finite: the colour window's centre moves by this many widths
//   window_scale        f64     8    finite, > 0: its width is multiplied by this
// A time series' playback keys (the window's Space, arrows, Home and End).
enum class TimeKey : uint8_t { None = 0, PlayPause, Forward, Back, First, Last, LastKey = Last };
struct Input {                                 // display -> master (interactive camera)
  uint64_t seq = 0;                            // echoed in FrameParams::input_seq
  double orbit_dx = 0, orbit_dy = 0;           // degrees
  double zoom = 1;                             // multiply eye distance
  std::optional<QualityName> quality;          // nullopt = unchanged
  bool interacting = false;                    // a drag (button held) or a wheel/resize burst goes on
  int width = 0, height = 0;                   // the window's new size (0: unchanged)
  TimeKey time = TimeKey::None;
  bool home = false;                           // the scene's camera and colour window again, then the rest
  double window_shift = 0, window_scale = 1;   // a right-button drag: the colour window's level and width
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
// `max_bytes`: the most decoded pixel bytes the receiver takes (its frame's worth): a part
// that claims more is refused before anything is allocated or decompressed (a few KB of
// zstd can claim 256 MB).
Result<Piece> decodePiece(std::span<const std::byte> msg, size_t max_bytes = SIZE_MAX);  // checks active within region, pixel count
Result<Strips> decodeStrips(std::span<const std::byte> msg, size_t max_bytes = SIZE_MAX);
Result<Framebuffer> decodeFramebuffer(std::span<const std::byte> msg, size_t max_bytes = SIZE_MAX);
Result<StageStats> decodeStageStats(std::span<const std::byte> msg);
Result<FrameDone> decodeFrameDone(std::span<const std::byte> msg);
Result<Input> decodeInput(std::span<const std::byte> msg);

}  // namespace tessera::proto
