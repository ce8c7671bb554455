// FrameParams on the wire: everything every stage needs to do its part of one frame.
// The decoder checks the cross-field invariants (order is a permutation, regions inside
// the image), so a stage can index with the decoded values without re-checking.
#include <cmath>
#include <algorithm>
#include <string>
#include <vector>

#include "common/wire/protocol.h"
#include "common/wire/protocol_internal.h"

namespace tessera::proto {

using detail::ByteReader;
using detail::ByteWriter;
using detail::readFinite;

namespace {

constexpr uint32_t kMaxBricks = 1 << 16;
constexpr uint32_t kMaxRegions = 1 << 16;
constexpr int kMaxVoxelIndex = 1 << 16;

void writeVec(ByteWriter& w, const Vec3& v) {
  w.f64(v.x);
  w.f64(v.y);
  w.f64(v.z);
}
Vec3 readVec(ByteReader& r, const char* field) {
  Vec3 v;
  v.x = readFinite(r, field);
  v.y = readFinite(r, field);
  v.z = readFinite(r, field);
  return v;
}

void writeCamera(ByteWriter& w, const Camera& c) {
  writeVec(w, c.eye);
  writeVec(w, c.target);
  writeVec(w, c.up);
  w.f64(c.fov);
  w.boolean(c.orthographic);
  w.f64(c.height);
}
Camera readCamera(ByteReader& r) {
  Camera c;
  c.eye = readVec(r, "camera.eye");
  c.target = readVec(r, "camera.target");
  c.up = readVec(r, "camera.up");
  c.fov = readFinite(r, "camera.fov");
  c.orthographic = r.boolean("camera.orthographic");
  c.height = readFinite(r, "camera.height");
  if (r.ok() && !(c.fov > 0 && c.fov < 180)) r.fail("camera.fov " + std::to_string(c.fov) + " not in (0,180)");
  if (r.ok() && !(c.height > 0)) r.fail("camera.height " + std::to_string(c.height) + " not positive");
  return c;
}

void writeQuality(ByteWriter& w, const Quality& q) {
  w.u8(static_cast<uint8_t>(q.name));
  w.f64(q.step);
  w.f64(q.early_termination);
  w.boolean(q.skip_empty);
  w.boolean(q.reference);
  w.boolean(q.jitter);
}
Quality readQuality(ByteReader& r) {
  Quality q;
  const uint8_t name = r.u8("quality.name");
  if (r.ok() && (name < 1 || name > static_cast<uint8_t>(QualityName::Last)))
    r.fail("quality.name " + std::to_string(name) + " not in 1.." + std::to_string(static_cast<int>(QualityName::Last)));
  q.name = static_cast<QualityName>(name);
  q.step = readFinite(r, "quality.step");
  q.early_termination = readFinite(r, "quality.early_termination");
  q.skip_empty = r.boolean("quality.skip_empty");
  q.reference = r.boolean("quality.reference");
  q.jitter = r.boolean("quality.jitter");
  if (r.ok() && !(q.step > 0)) r.fail("quality.step " + std::to_string(q.step) + " not positive");
  return q;
}

void readBricks(ByteReader& r, SortLastWork& m) {
  const uint32_t n = r.count("bricks", kMaxBricks, 4 + 24);
  m.bricks.resize(n);
  for (uint32_t i = 0; i < n && r.ok(); ++i) {
    BrickAssignment& b = m.bricks[i];
    b.renderer = r.u32("bricks.renderer");
    for (int a = 0; a < 3; ++a) b.brick.lo[a] = r.i32("bricks.lo");
    for (int a = 0; a < 3; ++a) b.brick.hi[a] = r.i32("bricks.hi");
    for (int a = 0; a < 3 && r.ok(); ++a) {
      if (b.brick.lo[a] < 0 || b.brick.lo[a] >= b.brick.hi[a] || b.brick.hi[a] > kMaxVoxelIndex) {
        r.fail("brick " + std::to_string(i) + " axis " + std::to_string(a) + ": lo " + std::to_string(b.brick.lo[a]) +
               " hi " + std::to_string(b.brick.hi[a]) + " not 0 <= lo < hi <= 65536");
      }
    }
  }
}

// A swap plan names every renderer of the bricks once, one brick each.
void readSwap(ByteReader& r, SortLastWork& m) {
  const uint32_t n = r.count("swap", kMaxBricks, 4 + 4 + 1);
  if (!r.ok() || n == 0) return;
  if (n != m.bricks.size()) {
    r.fail("swap has " + std::to_string(n) + " renderers for " + std::to_string(m.bricks.size()) +
           " bricks (needs one per brick)");
    return;
  }
  std::set<uint32_t> owners, named;
  for (const auto& b : m.bricks) owners.insert(b.renderer);
  if (owners.size() != n) return r.fail("swap with a renderer that owns more than one brick");
  m.swap.resize(n);
  for (uint32_t i = 0; i < n && r.ok(); ++i) {
    m.swap[i].renderer = r.u32("swap.renderer");
    m.swap[i].endpoint = r.str("swap.endpoint");
    if (!r.ok()) break;
    if (!owners.count(m.swap[i].renderer) || !named.insert(m.swap[i].renderer).second)
      return r.fail("swap names renderer " + std::to_string(m.swap[i].renderer) + " twice or without a brick");
    if (m.swap[i].endpoint.empty()) return r.fail("swap endpoint of renderer " + std::to_string(m.swap[i].renderer) + " is empty");
  }
}

void readOrder(ByteReader& r, SortLastWork& m) {
  const uint32_t n = r.count("order", kMaxBricks, 4);
  if (r.ok() && n != m.bricks.size()) {
    r.fail("order has " + std::to_string(n) + " entries for " + std::to_string(m.bricks.size()) + " bricks");
    return;
  }
  m.order.resize(n);
  std::vector<bool> seen(n, false);
  for (uint32_t i = 0; i < n && r.ok(); ++i) {
    int v = r.i32("order");
    if (!r.ok()) break;
    if (v < 0 || static_cast<uint32_t>(v) >= n || seen[v]) {
      r.fail("order is not a permutation (entry " + std::to_string(i) + " = " + std::to_string(v) + ")");
      break;
    }
    seen[v] = true;
    m.order[i] = v;
  }
}

void readTiles(ByteReader& r, const Rect& image, SortFirstWork& m) {
  const uint32_t n = r.count("tiles", 1u << 20, 8 + 16);
  m.tiles.resize(n);
  for (uint32_t i = 0; i < n && r.ok(); ++i) {
    TileAssignment& t = m.tiles[i];
    t.renderer = r.u32("tiles.renderer");
    t.compositor = r.u32("tiles.compositor");
    t.tile = detail::readRect(r, "tiles.tile");
    const Rect& g = t.tile;
    if (r.ok() && (g.w <= 0 || g.h <= 0 || g.x < 0 || g.y < 0 || g.x > image.w - g.w || g.y > image.h - g.h))
      r.fail("tile " + std::to_string(i) + " " + detail::rectText(t.tile) + " empty or outside image " + detail::rectText(image));
  }
}

void readRegions(ByteReader& r, FrameParams& m) {
  const uint32_t n = r.count("regions", kMaxRegions, 4 + 16 + 4);
  m.regions.resize(n);
  const Rect image{0, 0, m.width, m.height};
  for (uint32_t i = 0; i < n && r.ok(); ++i) {
    CompositorRegion& c = m.regions[i];
    c.compositor = r.u32("regions.compositor");
    c.region = detail::readRect(r, "regions.region");
    c.endpoint = r.str("regions.endpoint");
    if (!r.ok()) break;
    const Rect& g = c.region;
    if (g.x < 0 || g.y < 0 || g.w < 0 || g.h < 0 || g.x > image.w - g.w || g.y > image.h - g.h) {
      r.fail("region " + std::to_string(i) + " " + detail::rectText(g) + " outside image " + detail::rectText(image));
    }
  }
}

}  // namespace

std::vector<std::byte> encode(const FrameParams& m, uint32_t sender) {
  return detail::encodeStructured(Type::FrameParams, m.frame, sender, [&](ByteWriter& w) {
    w.u32(m.epoch);
    writeCamera(w, m.camera);
    writeQuality(w, m.quality);
    w.i32(m.width);
    w.i32(m.height);
    w.u8(static_cast<uint8_t>(m.codec));
    w.u8(static_cast<uint8_t>(m.format));
    w.u64(m.first_wanted);
    w.u64(m.input_seq);
    w.u64(m.input_first);
    w.boolean(m.interactive);
    w.u32(m.step);
    w.u32(m.next_step);
    w.f64(m.window.center);
    w.f64(m.window.width);
    w.u32(static_cast<uint32_t>(m.regions.size()));
    for (const CompositorRegion& c : m.regions) {
      w.u32(c.compositor);
      detail::writeRect(w, c.region);
      w.str(c.endpoint);
    }
    w.str(m.display_endpoint);
    w.u8(static_cast<uint8_t>(m.mode()));
    if (const auto* sl = std::get_if<SortLastWork>(&m.work)) {
      w.u32(static_cast<uint32_t>(sl->bricks.size()));
      for (const BrickAssignment& b : sl->bricks) {
        w.u32(b.renderer);
        for (int a = 0; a < 3; ++a) w.i32(b.brick.lo[a]);
        for (int a = 0; a < 3; ++a) w.i32(b.brick.hi[a]);
      }
      w.u32(static_cast<uint32_t>(sl->order.size()));
      for (int v : sl->order) w.i32(v);
      w.u32(static_cast<uint32_t>(sl->swap.size()));
      for (const SwapPeer& s : sl->swap) {
        w.u32(s.renderer);
        w.str(s.endpoint);
      }
    } else {
      const auto& sf = std::get<SortFirstWork>(m.work);
      w.u32(static_cast<uint32_t>(sf.tiles.size()));
      for (const TileAssignment& t : sf.tiles) {
        w.u32(t.renderer);
        w.u32(t.compositor);
        detail::writeRect(w, t.tile);
      }
    }
  });
}

std::set<uint32_t> renderersWithWork(const FrameParams& p) {
  std::set<uint32_t> r;
  if (const SortLastWork* work = p.sortLast())
    for (const auto& b : work->bricks) r.insert(b.renderer);
  if (const SortFirstWork* work = p.sortFirst())
    for (const auto& t : work->tiles) r.insert(t.renderer);
  return r;
}

Result<FrameParams> decodeFrameParams(std::span<const std::byte> msg) {
  return detail::decodeStructured<FrameParams>(
      msg, Type::FrameParams, [](ByteReader& r, const Header& h, FrameParams& m) {
        m.frame = h.frame;
        m.epoch = r.u32("epoch");
        m.camera = readCamera(r);
        m.quality = readQuality(r);
        m.width = r.i32("width");
        m.height = r.i32("height");
        if (r.ok() && (m.width < 1 || m.width > detail::kMaxDimension || m.height < 1 ||
                       m.height > detail::kMaxDimension)) {
          r.fail("image " + std::to_string(m.width) + "x" + std::to_string(m.height) + " not within 1..16384");
        }
        uint8_t codec = r.u8("codec");
        if (r.ok() && codec >= kCodecCount) r.fail("codec " + std::to_string(codec) + " unknown");
        m.codec = static_cast<Codec>(codec);
        uint8_t format = r.u8("format");
        if (r.ok() && !validPixelFormat(format)) r.fail("format " + std::to_string(format) + " unknown");
        m.format = static_cast<PixelFormat>(format);
        m.first_wanted = r.u64("first_wanted");
        if (r.ok() && m.first_wanted > m.frame)
          r.fail("first_wanted " + std::to_string(m.first_wanted) + " after the frame itself (" + std::to_string(m.frame) + ")");
        m.input_seq = r.u64("input_seq");
        m.input_first = r.u64("input_first");
        if (r.ok() && m.input_first > m.input_seq)
          r.fail("input_first " + std::to_string(m.input_first) + " after input_seq " + std::to_string(m.input_seq));
        m.interactive = r.boolean("interactive");
        m.step = r.u32("step");
        m.next_step = r.u32("next_step");
        if (r.ok() && std::max(m.step, m.next_step) >= 1000000)
          r.fail("step " + std::to_string(m.step) + " or next_step " + std::to_string(m.next_step) + " >= 1000000");
        m.window.center = detail::readFinite(r, "window.center");
        m.window.width = detail::readFinite(r, "window.width");
        constexpr double kLimit = ColorWindow::kLimit;
        if (r.ok() && !(std::abs(m.window.center) <= kLimit && m.window.width > 0 && m.window.width <= kLimit))
          r.fail("colour window centre " + std::to_string(m.window.center) + ", width " + std::to_string(m.window.width) +
                 " not within |centre| <= 1e6, 0 < width <= 1e6");
        readRegions(r, m);
        m.display_endpoint = r.str("display_endpoint");
        const uint8_t mode = r.u8("mode");
        if (!r.ok()) return;
        if (mode == static_cast<uint8_t>(FrameMode::SortLast)) {
          SortLastWork& sl = m.work.emplace<SortLastWork>();
          readBricks(r, sl);
          readOrder(r, sl);
          readSwap(r, sl);
          // A binary swap's bands go to the display: no compositor waits for pieces of it.
          if (r.ok() && !sl.swap.empty() && !m.regions.empty()) r.fail("a binary-swap frame with compositor regions");
        } else if (mode == static_cast<uint8_t>(FrameMode::SortFirst)) {
          readTiles(r, Rect{0, 0, m.width, m.height}, m.work.emplace<SortFirstWork>());
        } else {
          r.fail("mode " + std::to_string(mode) + " not in 1.." + std::to_string(static_cast<int>(FrameMode::Last)));
        }
      });
}

}  // namespace tessera::proto
