// tessera-traffic-bench: the bytes a sort-last frame puts on each link, for two compositing
// schedules, from the scene's real pieces (rendered here, encoded as the farm encodes them):
//  - direct send (the farm's): each renderer sends the part of its piece in each compositor's
//    band to that compositor, each compositor its finished band to the display;
//  - binary swap among the renderers (Cao et al., IceT): log2(R) rounds in which partners swap
//    halves of the band they hold, then each sends its finished band to the display.
// And two encodings of a piece: Up-filtered half floats + LZO (the farm's) against IceT's
// sparse form (runs of empty pixels per row, then the active pixels), LZO-coded. Messages are
// the farm's own (proto::encode of a Piece or Strips).
// Not a timed test: it prints KB per frame (and codec ms, one thread) for --views orbit views.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/bricks.h"
#include "common/clock.h"
#include "common/image.h"
#include "common/scene.h"
#include "common/volume.h"
#include "common/wire/codec.h"
#include "common/wire/pixels.h"
#include "common/wire/protocol.h"
#include "common/wire/strips.h"
#include "renderer/volume/backend.h"

using namespace tessera;

namespace {

Rect rows(int y0, int y1, int width) { return y1 > y0 ? Rect{0, y0, width, y1 - y0} : Rect{}; }

// The Piece message a renderer sends for `band` of its image (the farm's format and codec:
// rgba16f, Up filter, LZO); no message when nothing in the band is active.
std::vector<std::byte> pieceMessage(const ImageF& img, const Rect& band) {
  proto::Piece p;
  p.region = band;
  p.active = intersect(activeRegion(img), band);
  if (p.active.empty()) return {};
  p.format = proto::PixelFormat::RGBA16F;
  p.pixels = packPixels(img, p.active, p.format);
  return proto::encode(p, 0, Codec::Lzo);
}
size_t pieceBytes(const ImageF& img, const Rect& band) { return pieceMessage(img, band).size(); }

// The Strips message of a finished band to the display (rgba8 strips, LZO).
size_t bandBytes(const Image8& frame, const Rect& band) {
  proto::Strips s;
  s.stream = encodeStrips(frame, band, 0);
  return proto::encode(s, 0, Codec::Lzo).size();
}

ImageF over(const ImageF& front, const ImageF& back) {
  ImageF o = front;
  compositeOver(o, back, Rect{0, 0, front.width, front.height});
  return o;
}

// Link bytes of one frame: what each host sends and receives.
struct Links {
  std::map<std::string, double> out, in;
  void send(const std::string& from, const std::string& to, double bytes) { out[from] += bytes, in[to] += bytes; }
  std::pair<std::string, double> busiest() const {
    std::pair<std::string, double> b{"", 0};
    for (const auto& [k, v] : out) if (v > b.second) b = {k + " sends", v};
    for (const auto& [k, v] : in) if (v > b.second) b = {k + " receives", v};
    return b;
  }
  double total() const {
    double t = 0;
    for (const auto& [k, v] : out) t += v;
    return t;
  }
};

// pieces[i]: the i-th nearest brick's image; `act` the frame's active rows; C compositors.
Links directSend(const std::vector<ImageF>& pieces, const Image8& frame, const Rect& act, int compositors) {
  Links l;
  for (int c = 0; c < compositors; ++c) {
    const Rect band = rows(act.y + act.h * c / compositors, act.y + act.h * (c + 1) / compositors, frame.width);
    const std::string comp = "compositor-" + std::to_string(c + 1);
    for (size_t r = 0; r < pieces.size(); ++r) l.send("renderer-" + std::to_string(r + 1), comp, pieceBytes(pieces[r], band));
    l.send(comp, "display", bandBytes(frame, band));
  }
  return l;
}

// Renderer r holds rows [lo[r], hi[r]) of the image of its group; partners differ in bit j of
// their rank (visibility order), so a group is a run of nearest-first ranks and the lower
// rank's group is in front.
Links binarySwap(std::vector<ImageF> held, const Image8& frame, const Rect& act) {
  Links l;
  const int n = (int)held.size();
  std::vector<int> lo(n, act.y), hi(n, act.y + act.h);
  for (int bit = 1; bit < n; bit <<= 1) {
    std::vector<ImageF> next(n);
    for (int r = 0; r < n; ++r) {
      const int p = r ^ bit, mid = (lo[r] + hi[r]) / 2;
      const bool front = r < p;  // keeps the upper half
      const Rect give = front ? rows(mid, hi[r], frame.width) : rows(lo[r], mid, frame.width);
      l.send("renderer-" + std::to_string(r + 1), "renderer-" + std::to_string(p + 1), pieceBytes(held[r], give));
      next[r] = front ? over(held[r], held[p]) : over(held[p], held[r]);
    }
    for (int r = 0; r < n; ++r) {
      const int mid = (lo[r] + hi[r]) / 2;
      ((r < (r ^ bit)) ? hi[r] : lo[r]) = mid;
    }
    held = std::move(next);
  }
  for (int r = 0; r < n; ++r) l.send("renderer-" + std::to_string(r + 1), "display", bandBytes(frame, rows(lo[r], hi[r], frame.width)));
  return l;
}

// IceT's sparse piece: per row, (empty run, active run) 16-bit pairs, then the active pixels'
// half floats as two byte planes; both LZO-coded. Returns the bytes.
size_t sparseBytes(const ImageF& img, double& encode_ms, double& decode_ms) {
  const Rect a = activeRegion(img);
  if (a.empty()) return 0;
  const auto t0 = std::chrono::steady_clock::now();
  const auto packed = packPixels(img, a, proto::PixelFormat::RGBA16F);  // low bytes, then high bytes
  const size_t n = (size_t)a.w * a.h;
  const std::byte* plane[2] = {packed.data(), packed.data() + 4 * n};
  std::vector<uint16_t> runs;
  std::vector<std::byte> active[2];
  auto empty = [&](size_t p) {
    uint32_t x, y;
    std::memcpy(&x, plane[0] + 4 * p, 4), std::memcpy(&y, plane[1] + 4 * p, 4);
    return (x | y) == 0;
  };
  for (int y = 0; y < a.h; ++y)
    for (int x = 0; x < a.w;) {
      int e = 0, k = 0;
      for (; x < a.w && empty((size_t)y * a.w + x); ++x) ++e;
      for (; x < a.w && !empty((size_t)y * a.w + x); ++x, ++k)
        for (int b = 0; b < 2; ++b) active[b].insert(active[b].end(), plane[b] + 4 * ((size_t)y * a.w + x), plane[b] + 4 * ((size_t)y * a.w + x) + 4);
      runs.push_back((uint16_t)e), runs.push_back((uint16_t)k);
    }
  std::vector<std::byte> planes(active[0]);
  planes.insert(planes.end(), active[1].begin(), active[1].end());
  const auto run_bytes = std::as_bytes(std::span(runs));
  const auto enc_planes = compress(Codec::Lzo, planes), enc_runs = compress(Codec::Lzo, run_bytes);
  encode_ms += msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  std::vector<std::byte> dec_planes(planes.size()), dec_runs(run_bytes.size()), full(packed.size());
  (void)decompressInto(Codec::Lzo, enc_planes, dec_planes);
  (void)decompressInto(Codec::Lzo, enc_runs, dec_runs);
  const size_t na = planes.size() / 8;
  size_t pix = 0, k = 0;
  for (size_t i = 0; i + 1 < runs.size(); i += 2) {
    pix += runs[i];
    for (int j = 0; j < runs[i + 1]; ++j, ++pix, ++k)
      for (int b = 0; b < 2; ++b) std::memcpy(&full[b * 4 * n + 4 * pix], &dec_planes[b * 4 * na + 4 * k], 4);
  }
  decode_ms += msSince(t1);
  if (full != packed) throw std::runtime_error("sparse piece does not decode to the piece");
  return enc_planes.size() + enc_runs.size() + proto::encode(proto::Piece{}, 0, Codec::Lzo).size();  // + a Piece's header
}

// The farm's piece of the whole image: bytes, encode and decode (proto::decodePiece) times.
size_t upFilteredBytes(const ImageF& img, double& encode_ms, double& decode_ms) {
  const Rect all{0, 0, img.width, img.height};
  const auto t0 = std::chrono::steady_clock::now();
  const auto msg = pieceMessage(img, all);
  encode_ms += msSince(t0);
  if (msg.empty()) return 0;
  const auto t1 = std::chrono::steady_clock::now();
  if (!proto::decodePiece(msg)) throw std::runtime_error("a piece does not decode");
  decode_ms += msSince(t1);
  return msg.size();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Bytes per link of a sort-last frame: direct send against binary swap; piece encodings"};
  std::string scene_path;
  int renderers = 4, compositors = 2, views = 6, size = 1024;
  app.add_option("scene", scene_path, "scene file (default: the built-in scene)");
  // The model's binary swap has no radix-k rounds (the farm's has): a power of two.
  app.add_option("--renderers", renderers, "bricks, one per renderer (a power of two)")->check(CLI::Range(2, 64));
  app.add_option("--compositors", compositors, "compositors of the direct send")->check(CLI::Range(1, 64));
  app.add_option("--views", views, "orbit views, evenly spaced")->check(CLI::Range(1, 360));
  app.add_option("--image", size, "image side in pixels")->check(CLI::Range(16, 8192));
  CLI11_PARSE(app, argc, argv);
  if (renderers & (renderers - 1)) {
    std::fprintf(stderr, "tessera-traffic-bench: --renderers must be a power of two (binary swap), got %d\n", renderers);
    return 2;
  }
  Scene scene = scene_path.empty() ? defaultScene() : loadScene(scene_path);
  if (scene.blend != Blend::Composite) {  // its pieces are blended "over" below
    std::fprintf(stderr, "tessera-traffic-bench: composite scenes only, not blend: %s\n", blendName(scene.blend));
    return 2;
  }
  auto vol = std::make_shared<const Volume>(loadVolume(scene, VoxelBox{{0, 0, 0}, volumeDims(scene)}, 0));
  scene.tf = windowed(scene.tf, colorWindow(scene, vol->mapped_range));  // the scene's `window`, as the farm shows it
  auto backend = renderer::makeVolumeBackend(renderer::BackendKind::Cpu, vol, scene.tf, scene.shading, scene.light,
                                             Blend::Composite, scene.crop);
  const BrickTree tree = splitBricks(*vol, renderers, &scene.tf);
  renderer::RenderOptions opt;
  opt.quality = scene.quality;
  std::printf("view,schedule,busiest,busiest_kb,all_links_kb\n");
  double sum[2][2] = {};
  double up_kb = 0, up_enc = 0, up_dec = 0, sp_kb = 0, sp_enc = 0, sp_dec = 0;
  for (int v = 0; v < views; ++v) {
    const int frame = v * std::max(1, scene.orbit.frames / views);
    const Camera cam = scene.orbit.at(scene.camera, frame);
    std::vector<ImageF> pieces;
    for (int leaf : tree.visibilityOrder(*vol, cam)) pieces.push_back(backend->render(cam, size, size, tree.bricks[leaf], opt));
    ImageF image = pieces[0];
    for (size_t r = 1; r < pieces.size(); ++r) image = over(image, pieces[r]);
    const Rect act = activeRegion(image);
    const Image8 frame8 = toRGBA8(image);
    const Links links[2] = {directSend(pieces, frame8, act, compositors), binarySwap(pieces, frame8, act)};
    for (int s = 0; s < 2; ++s) {
      const auto [who, bytes] = links[s].busiest();
      std::printf("%d,%s,%s,%.0f,%.0f\n", frame, s ? "binary-swap" : "direct-send", who.c_str(), bytes / 1e3, links[s].total() / 1e3);
      sum[s][0] += bytes, sum[s][1] += links[s].total();
    }
    for (const auto& p : pieces) {
      up_kb += upFilteredBytes(p, up_enc, up_dec) / 1e3;
      sp_kb += sparseBytes(p, sp_enc, sp_dec) / 1e3;
    }
  }
  std::printf("\nper frame, mean of %d views, %dx%d, %d renderers:\n", views, size, size, renderers);
  std::printf("  direct send to %d compositors: busiest link %.0f KB, all links %.0f KB\n", compositors, sum[0][0] / views / 1e3, sum[0][1] / views / 1e3);
  std::printf("  binary swap, no compositors:  busiest link %.0f KB, all links %.0f KB\n", sum[1][0] / views / 1e3, sum[1][1] / views / 1e3);
  std::printf("pieces per frame (one thread): Up-filtered LZO %.0f KB, encode %.1f ms, decode %.1f ms; "
              "sparse (IceT) LZO %.0f KB, encode %.1f ms, decode %.1f ms\n",
              up_kb / views, up_enc / views, up_dec / views, sp_kb / views, sp_enc / views, sp_dec / views);
}
