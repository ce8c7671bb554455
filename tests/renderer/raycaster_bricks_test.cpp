// Sort-last arithmetic in one process: bricks rendered separately and composited front to
// back in BrickTree::visibilityOrder must reproduce the whole-volume image.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "common/bricks.h"
#include "renderer/volume/raycaster.h"
#include "tests/renderer/render_test_util.h"

namespace tessera::renderer {
namespace {

using test::defaultTf;
using test::options;

ImageF compositeBricks(const Raycaster& rc, const Volume& vol, const TransferFunction& tf, const Camera& cam, int w,
                       int h, int n, const RenderOptions& opt, int* rendered = nullptr) {
  const BrickTree tree = splitBricks(vol, n, &tf);
  ImageF out(w, h);
  int count = 0;
  for (int leaf : tree.visibilityOrder(vol, cam)) {
    Rect active;
    const ImageF part = rc.render(cam, w, h, tree.bricks[leaf], opt, nullptr, &active);
    EXPECT_EQ(active, activeRegion(part));
    if (!active.empty()) compositeOver(out, part, active);
    ++count;
  }
  if (rendered) *rendered = count;
  return out;
}

struct BrickCase {
  const char* generator;
  int size;
  int frame;
};

class BricksVsWhole : public ::testing::TestWithParam<BrickCase> {};

// docs/DESIGN.md contract: sort-last vs one process, any brick split, rgba8: max abs <= 1/255.
// Every brick takes exactly the whole image's samples (one global grid per ray), so only
// float compositing order differs. Early termination is disabled here: a brick cannot
// see the opacity in front of it, so with ET at 0.99 the split image legitimately gains up
// to 0.01 of light the whole image dropped (checked separately below).
TEST_P(BricksVsWhole, MaxAbsWithinOneLevel) {
  const BrickCase c = GetParam();
  auto vol = test::generated(c.generator, c.size);
  const TransferFunction tf = defaultTf();
  const Raycaster rc(vol, tf);
  const Camera cam = Orbit{12, {0.2, 1, 0.1}}.at(test::defaultCamera(), c.frame);
  RenderOptions opt = options("default");
  opt.quality.early_termination = 2.0;
  const ImageF whole = rc.render(cam, 64, 56, wholeVolume(*vol), opt);
  ASSERT_GT(activeRegion(whole).area(), 200);
  for (int n : {1, 2, 3, 8}) {
    int rendered = 0;
    const ImageF split = compositeBricks(rc, *vol, tf, cam, 64, 56, n, opt, &rendered);
    EXPECT_EQ(rendered, n);
    const ImageError e = compare(toRGBA8(split), toRGBA8(whole));
    EXPECT_LE(e.max_abs, 1.0 / 255 + 1e-12)
        << n << " bricks; see " << test::dumpImages(std::string("bricks_") + c.generator + std::to_string(n), whole, split);
  }
}

INSTANTIATE_TEST_SUITE_P(Generators, BricksVsWhole,
                         ::testing::Values(BrickCase{"hollow-shell", 40, 0}, BrickCase{"noise-cloud", 37, 3},
                                           BrickCase{"marschner-lobb", 33, 5}));

TEST(BricksVsWhole, DefaultQualityWithEarlyTerminationStaysWithinItsBound) {
  auto vol = test::generated("hollow-shell", 40);
  const TransferFunction tf = defaultTf();
  const Raycaster rc(vol, tf);
  const RenderOptions opt = options("default");
  const ImageF whole = rc.render(test::defaultCamera(), 64, 64, wholeVolume(*vol), opt);
  const ImageF split = compositeBricks(rc, *vol, tf, test::defaultCamera(), 64, 64, 8, opt);
  // Bound: the light a terminated whole-volume ray drops (1 - threshold), plus rgba8 rounding.
  const double dropped = std::max(0.0, 1.0 - opt.quality.early_termination);
  EXPECT_LE(compare(toRGBA8(split), toRGBA8(whole)).max_abs, dropped + 1.0 / 255 + 1e-12);
}

TEST(BricksVsWhole, EyeInsideTheVolume) {
  auto vol = test::generated("noise-cloud", 32);
  const TransferFunction tf = defaultTf();
  const Raycaster rc(vol, tf);
  const Camera cam{{0.05, 0.02, 0.1}, {0.3, -0.2, -1}, {0, 1, 0}, 70, false, 1};
  RenderOptions opt = options("default");
  opt.quality.early_termination = 2.0;
  const ImageF whole = rc.render(cam, 48, 40, wholeVolume(*vol), opt);
  ASSERT_TRUE(test::allFinite(whole));
  ASSERT_GT(activeRegion(whole).area(), 100);
  const ImageF split = compositeBricks(rc, *vol, tf, cam, 48, 40, 5, opt);
  EXPECT_LE(compare(toRGBA8(split), toRGBA8(whole)).max_abs, 1.0 / 255 + 1e-12);
}

TEST(BricksVsWhole, SkippingIsBitIdenticalPerBrick) {
  auto vol = test::generated("hollow-shell", 48);
  const TransferFunction tf = defaultTf();
  const Raycaster rc(vol, tf);
  RenderOptions on = options("default"), off = options("default");
  off.quality.skip_empty = false;
  for (const BrickBox& b : splitBricks(*vol, 3, &tf).bricks)
    EXPECT_TRUE(rc.render(test::defaultCamera(), 48, 48, b, on) == rc.render(test::defaultCamera(), 48, 48, b, off));
}

// A renderer passes the image it no longer needs as the next one's memory: what was in it
// (another brick, another size) must not show through. Two dense cubes in opposite corners:
// between them lie pixels of the active rectangle that no ray is cast for.
TEST(BricksVsWhole, ARecycledImageGivesTheSameImage) {
  auto vol = std::make_shared<Volume>();
  vol->dims = {32, 32, 32};
  vol->values.assign(vol->voxelCount(), 0.0f);
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        if ((x < 8 && y < 8 && z < 8) || (x >= 24 && y >= 24 && z >= 24)) vol->values[vol->index(x, y, z)] = 0.8f;
  const TransferFunction tf = defaultTf();
  const Raycaster rc(vol, tf);
  const RenderOptions opt = options("default");
  const BrickBox whole{{0, 0, 0}, {32, 32, 32}};
  ImageF junk(64, 64);
  std::fill(junk.px.begin(), junk.px.end(), 0.75f);
  const float* memory = junk.px.data();
  Rect fresh_active, recycled_active;
  const ImageF fresh = rc.render(test::defaultCamera(), 48, 40, whole, opt, nullptr, &fresh_active);
  const ImageF recycled = rc.render(test::defaultCamera(), 48, 40, whole, opt, nullptr, &recycled_active, std::move(junk));
  EXPECT_EQ(recycled.px.data(), memory) << "the recycled memory is used";
  EXPECT_EQ(recycled_active, fresh_active);
  EXPECT_TRUE(recycled == fresh);
  int clear = 0;
  for (int y = fresh_active.y; y < fresh_active.y + fresh_active.h; ++y)
    for (int x = fresh_active.x; x < fresh_active.x + fresh_active.w; ++x) clear += fresh.at(x, y)[3] == 0;
  EXPECT_GT(clear, fresh_active.area() / 4) << "the case has transparent pixels in the active rectangle";
}

}  // namespace
}  // namespace tessera::renderer
