// OSMesa backend: tiles bit-identical to full frames (any tiling, samples 1 and 4, supersampling),
// chunk culling exactness, extreme geometry, anti-aliasing and the FFT post filter.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "common/io/image_io.h"
#include "renderer/tools/fft_filter.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/mesh/marching_cubes.h"

namespace tessera::renderer {
namespace {

// One context for the suite: creating one costs ~25 ms.
GlRenderer& gl() {
  static GlRenderer r;
  return r;
}

// Two blobs of different colours (sum of two spheres' fields), chunked: many small chunks so
// that culling leaves chunks out of most tiles.
struct ChunkedMesh {
  Mesh mesh;
  std::vector<Chunk> chunks;
};
const ChunkedMesh& blobs() {
  static const ChunkedMesh s = [] {
    Volume v;
    const int n = 36;
    v.dims = {n, n, n};
    v.values.resize(v.voxelCount());
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const Vec3 p = v.boxMin() + Vec3{(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n};
          const double a = length(p - Vec3{-0.15, 0.05, 0}), b = length(p - Vec3{0.2, -0.1, 0.1});
          v.values[v.index(x, y, z)] = (float)(0.02 / (a * a + 0.01) + 0.01 / (b * b + 0.005));
        }
    ChunkedMesh out;
    out.mesh = marchingCubes(v, 0.45f, {0.9f, 0.5f, 0.2f});
    // Vary colours per vertex so that interpolation is exercised.
    for (size_t i = 0; i < out.mesh.vertexCount(); ++i) out.mesh.colors[3 * i + 2] = 0.5f + 0.5f * out.mesh.positions[3 * i];
    out.chunks = buildChunks(out.mesh, 64);
    return out;
  }();
  return s;
}

const Camera kCamera{{0.4, 0.5, 1.9}, {0, 0, 0}, {0, 1, 0}, 35};

void dumpOnFailure(const Image8& expected, const Image8& actual, const std::string& name) {
  if (expected == actual) return;
  const auto dir = std::filesystem::temp_directory_path() / "tessera_gl_renderer_test";
  std::filesystem::create_directories(dir);
  writePng((dir / (name + "_expected.png")).string(), expected);
  writePng((dir / (name + "_actual.png")).string(), actual);
  ADD_FAILURE() << name << ": images differ; PNGs in " << dir;
}

int coverage(const Image8& img) {
  int n = 0;
  for (size_t i = 3; i < img.px.size(); i += 4) n += img.px[i] > 0;
  return n;
}

Image8 fullFrame(const Camera& cam, int w, int h, const GlRenderOptions& opt) {
  gl().setMesh(blobs().mesh);
  return gl().render(cam, w, h, Rect{0, 0, w, h}, blobs().chunks, opt);
}

TEST(GlRendererTest, FullFrameShowsTheMeshPremultiplied) {
  const Image8 img = fullFrame(kCamera, 97, 83, {});
  const int cov = coverage(img);
  EXPECT_GT(cov, 97 * 83 / 10);  // the blobs fill a good part of the view
  EXPECT_LT(cov, 97 * 83);       // and leave background
  for (size_t i = 0; i < img.px.size(); i += 4) {
    ASSERT_TRUE(img.px[i + 3] == 0 || img.px[i + 3] == 255) << "samples 1: no partial coverage";
    for (int c = 0; c < 3; ++c) ASSERT_LE(img.px[i + c], img.px[i + 3]) << "premultiplied";
  }
  // Lit: the nearest surface (facing the headlight) is brighter than ambient alone.
  int brightest = 0;
  for (size_t i = 0; i < img.px.size(); i += 4) brightest = std::max<int>(brightest, img.px[i]);
  EXPECT_GT(brightest, 200);
}

struct TilingCase {
  int w, h;
  std::vector<Rect> tiles;
  const char* name;
};

std::vector<TilingCase> tilings() {
  std::vector<TilingCase> cases;
  for (auto [w, h] : {std::pair{64, 48}, std::pair{97, 83}}) {
    cases.push_back({w, h, gridTiles(w, h, 2, 2), "2x2"});
    cases.push_back({w, h, gridTiles(w, h, 3, 5), "3x5"});
    cases.push_back({w, h, gridTiles(w, h, 7, 1), "7x1"});
    // Non-uniform, with one-pixel-wide and one-pixel-high tiles.
    cases.push_back({w, h,
                     {{0, 0, 1, h}, {1, 0, w / 2 - 1, 1}, {1, 1, w / 2 - 1, h - 1}, {w / 2, 0, w - w / 2, h / 3},
                      {w / 2, h / 3, 1, h - h / 3}, {w / 2 + 1, h / 3, w - w / 2 - 1, h - h / 3}},
                     "non-uniform"});
  }
  return cases;
}

TEST(GlRendererTest, TilesAreBitIdenticalToTheFullFrame) {
  for (int samples : {1, 4})
    for (const auto& tc : tilings()) {
      GlRenderOptions opt;
      opt.samples = samples;
      const Image8 full = fullFrame(kCamera, tc.w, tc.h, opt);
      GlRenderStats st;
      const Image8 tiled = renderTiles(gl(), kCamera, tc.w, tc.h, tc.tiles, blobs().chunks, opt, &st);
      dumpOnFailure(full, tiled,
                    std::string(tc.name) + "_" + std::to_string(tc.w) + "x" + std::to_string(tc.h) + "_s" +
                        std::to_string(samples));
      // The tiles cover the image exactly: the assembled image has the full frame's coverage.
      EXPECT_EQ(coverage(tiled), coverage(full));
    }
}

TEST(GlRendererTest, SupersampledAndOrthographicTilesAreBitIdentical) {
  GlRenderOptions opt;
  opt.supersample = 2;
  opt.samples = 4;
  const Image8 full = fullFrame(kCamera, 64, 48, opt);
  dumpOnFailure(full, renderTiles(gl(), kCamera, 64, 48, gridTiles(64, 48, 3, 2), blobs().chunks, opt), "ssaa2_msaa4");
  Camera ortho = kCamera;
  ortho.orthographic = true;
  ortho.height = 1.1;
  opt = {};
  const Image8 ofull = fullFrame(ortho, 97, 83, opt);
  EXPECT_GT(coverage(ofull), 97 * 83 / 10);
  dumpOnFailure(ofull, renderTiles(gl(), ortho, 97, 83, gridTiles(97, 83, 4, 3), blobs().chunks, opt), "ortho");
}

TEST(GlRendererTest, CulledChunksWouldDrawNothingInTheTile) {
  gl().setMesh(blobs().mesh);
  const int w = 97, h = 83;
  const ViewProjection vp = gl().viewProjection(kCamera, w, h);
  size_t culled_total = 0;
  for (const Rect& t : gridTiles(w, h, 4, 4)) {
    std::vector<Chunk> in, out;
    const auto ids = chunksInTile(blobs().chunks, vp, t);
    for (size_t i = 0, j = 0; i < blobs().chunks.size(); ++i) {
      if (j < ids.size() && ids[j] == (int)i) {
        in.push_back(blobs().chunks[i]);
        ++j;
      } else {
        out.push_back(blobs().chunks[i]);
      }
    }
    culled_total += out.size();
    GlRenderStats s_in, s_all;
    // Same bytes with or without the culled chunks, and the culled chunks alone leave it empty.
    const Image8 a = gl().render(kCamera, w, h, t, in, {4}, &s_in);
    const Image8 b = gl().render(kCamera, w, h, t, blobs().chunks, {4}, &s_all);
    dumpOnFailure(b, a, "culling");
    if (!out.empty()) {
      EXPECT_EQ(coverage(gl().render(kCamera, w, h, t, out, {4})), 0);
    }
    uint64_t culled_triangles = 0;
    for (const Chunk& c : out) culled_triangles += c.triangle_count;
    EXPECT_EQ(s_in.triangles + culled_triangles, s_all.triangles);
  }
  // Culling does something: with 16 tiles most chunks miss most tiles.
  EXPECT_GT(culled_total, blobs().chunks.size() * 8);
}

TEST(GlRendererTest, MsaaAndSupersamplingSmoothEdges) {
  auto partial = [](const Image8& img) {
    int n = 0;
    for (size_t i = 3; i < img.px.size(); i += 4) n += img.px[i] > 0 && img.px[i] < 255;
    return n;
  };
  GlRenderOptions opt;
  EXPECT_EQ(partial(fullFrame(kCamera, 64, 48, opt)), 0);
  opt.samples = 4;
  const Image8 msaa = fullFrame(kCamera, 64, 48, opt);
  EXPECT_GT(partial(msaa), 20);  // the silhouette has partial pixels
  opt.samples = 2;               // llvmpipe renders 2 as 4
  EXPECT_EQ(fullFrame(kCamera, 64, 48, opt), msaa);
  opt = {};
  opt.supersample = 3;
  EXPECT_GT(partial(fullFrame(kCamera, 64, 48, opt)), 20);
}

TEST(GlRendererTest, ExtremeGeometryRendersWithoutCrashing) {
  GlRenderer& r = gl();
  Mesh m;
  auto vertex = [&](double x, double y, double z) {
    m.positions.insert(m.positions.end(), {(float)x, (float)y, (float)z});
    m.colors.insert(m.colors.end(), {1.f, 1.f, 1.f});
  };
  // Degenerate: a point triangle and a collinear one; then a huge triangle behind the origin
  // covering the whole view.
  vertex(0, 0, 0), vertex(0, 0, 0), vertex(0, 0, 0);
  vertex(0, 0, 0), vertex(0.1, 0.1, 0), vertex(0.2, 0.2, 0);
  vertex(-1e6, -1e6, -1), vertex(1e6, -1e6, -1), vertex(0, 1e6, -1);
  m.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  computeSmoothNormals(m);
  const auto chunks = buildChunks(m, 1);  // before setMesh: it reorders the triangles
  r.setMesh(m);
  const Camera cam{{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 40};
  for (int samples : {1, 4}) {
    const Image8 img = r.render(cam, 64, 48, {0, 0, 64, 48}, {samples});
    EXPECT_EQ(coverage(img), 64 * 48) << "the huge triangle covers the view";
    dumpOnFailure(img, renderTiles(r, cam, 64, 48, gridTiles(64, 48, 5, 3), chunks, {samples}), "huge");
  }
  // Coordinates near the float limit: clipped by GL, no crash.
  for (float& p : m.positions) p *= 1e30f;
  r.setMesh(m);
  EXPECT_NO_THROW(r.render(cam, 64, 48, {0, 0, 64, 48}, {4}));
}

TEST(GlRendererTest, CameraInsideAClosedMeshSeesItEverywhere) {
  Volume v;
  v.dims = {24, 24, 24};
  v.values.resize(v.voxelCount());
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x)
        v.values[v.index(x, y, z)] = (float)length(v.boxMin() + Vec3{(x + 0.5) / 24, (y + 0.5) / 24, (z + 0.5) / 24});
  Mesh sphere = marchingCubes(v, 0.4f);  // values grow outwards: the sphere of radius 0.4
  gl().setMesh(sphere);
  const Camera cam{{0.05, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90};
  const Image8 img = gl().render(cam, 64, 48, {0, 0, 64, 48}, {4});
  EXPECT_EQ(coverage(img), 64 * 48);
  int dark = 0;
  for (size_t i = 0; i < img.px.size(); i += 4) dark += img.px[i] < 0.2 * 255;
  EXPECT_EQ(dark, 0) << "two-sided lighting: inside faces are lit, never below ambient";
}

TEST(GlRendererTest, BadArgumentsAreClearErrors) {
  gl().setMesh(blobs().mesh);
  EXPECT_THROW(gl().render(kCamera, 64, 48, {0, 0, 64, 48}, {3}), std::invalid_argument);
  EXPECT_THROW(gl().render(kCamera, 64, 48, {60, 0, 5, 48}, GlRenderOptions{}), std::invalid_argument);
  EXPECT_THROW(gl().render(kCamera, 64, 48, {0, 0, 0, 0}, GlRenderOptions{}), std::invalid_argument);
  GlRenderOptions opt;
  opt.supersample = 9;
  EXPECT_THROW(gl().render(kCamera, 64, 48, {0, 0, 64, 48}, opt), std::invalid_argument);
  Mesh empty;
  EXPECT_THROW(gl().setMesh(empty), std::runtime_error);
}

TEST(FftFilterTest, ConstantStaysAndAnEdgeIsBlurred) {
  Image8 flat(33, 20);
  for (size_t i = 0; i < flat.px.size(); i += 4) flat.px[i] = 100, flat.px[i + 3] = 200;
  Image8 f = flat;
  lowPassFilter(f, 1.5);
  EXPECT_EQ(f, flat);  // edge replication: no border darkening; round trip exact to 1/255 rounding
  Image8 edge(32, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 16; x < 32; ++x) edge.at(x, y)[3] = 255, edge.at(x, y)[0] = 255;
  Image8 g = edge;
  lowPassFilter(g, 1.0);
  EXPECT_GT(g.at(15, 4)[3], 40);   // Gaussian sigma 1: ~31% of the step one pixel out
  EXPECT_LT(g.at(16, 4)[3], 215);
  EXPECT_EQ(g.at(0, 4)[3], 0);     // no wrap-around from the opposite edge
  EXPECT_EQ(g.at(31, 4)[3], 255);
  Image8 same = edge;
  lowPassFilter(same, 0);
  EXPECT_EQ(same, edge);
  EXPECT_THROW(lowPassFilter(same, -1), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::renderer
