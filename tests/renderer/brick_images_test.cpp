// What a volume renderer holds and renders (renderer/brick_images.h): a frame whose inputs
// did not change reuses its image, and the image a binary swap's rounds still read is never
// recycled while the next frame renders (its memory and pixels stay as they were).
#include <gtest/gtest.h>

#include <vector>

#include "common/volume_summary.h"
#include "renderer/brick_images.h"

namespace tessera::renderer {
namespace {

// A 32^3 shell seen by `side` x `side` frames; at(x) pans the camera by x along the x axis.
struct Shell {
  Scene scene;
  proto::FrameParams p;
  explicit Shell(int side) {
    scene = defaultScene();
    scene.volume = GeneratorSpec{"hollow-shell", 32, 1, {1, 1, 1}};
    fixVolumeRange(scene);
    p.width = p.height = side;
    p.camera = scene.camera;
    p.quality = scene.quality;
  }
  proto::FrameParams at(double x, bool pan = false) const {
    proto::FrameParams q = p;
    q.camera.eye[0] += x;
    if (pan) q.camera.target[0] += x;
    return q;
  }
};

TEST(BrickImages, AnUnchangedFrameIsReusedAndTheImageInTheRoundsIsNeverRecycled) {
  const Shell shell(24);
  BrickImages images(shell.scene, BackendKind::Cpu, 64, 1);
  proto::SortLastWork work;
  const BrickBox brick{{0, 0, 0}, {32, 32, 32}};
  work.bricks.push_back({0, brick});
  proto::StageStats st;
  images.hold(shell.p, work, 0, st);
  auto at = [&](double x) { return shell.at(x); };

  const BrickImages::Image& a = images.render(at(0), brick, st, nullptr);
  EXPECT_EQ(&images.render(at(0), brick, st, nullptr), &a) << "unchanged inputs: the same image";
  EXPECT_EQ(st.images_made, 1u);
  EXPECT_EQ(st.images_reused, 1u);
  const std::vector<float> pixels = a.image.px;
  const float* memory = a.image.px.data();
  ASSERT_GT(a.active.area(), 0) << "the shell is in view";

  images.render(at(0.2), brick, st, nullptr);  // b
  const BrickImages::Image& c = images.render(at(0.4), brick, st, &a);  // a's rounds still read it
  // b, not a, made room for c: a is still there to reuse (checked before a is read again).
  ASSERT_EQ(st.images_made, 3u);
  ASSERT_EQ(&images.render(at(0), brick, st, &c), &a);
  ASSERT_EQ(st.images_made, 3u) << "a was recycled while its rounds read it";
  EXPECT_EQ(a.image.px.data(), memory) << "the image in the rounds kept its memory";
  EXPECT_EQ(a.image.px, pixels) << "and its pixels";
  images.render(at(0.2), brick, st, &c);
  EXPECT_EQ(st.images_made, 4u) << "b was recycled, so it is rendered again";
}

// A recycled image is rendered into as it is (clearing all of it was 2% of a farm renderer's
// time): what it drew before must be gone, and the image equal to one rendered fresh.
TEST(BrickImages, ARecycledImageEqualsAFreshOne) {
  const Shell shell(40);
  proto::SortLastWork work;
  const BrickBox brick{{0, 0, 0}, {32, 32, 16}};
  work.bricks.push_back({0, brick});
  auto at = [&](double x) { return shell.at(x, true); };  // a pan: the brick moves across the image
  proto::StageStats st;
  BrickImages fresh(shell.scene, BackendKind::Cpu, 64, 1), reused(shell.scene, BackendKind::Cpu, 64, 1);
  fresh.hold(shell.p, work, 0, st);
  reused.hold(shell.p, work, 0, st);
  const BrickImages::Image& first = reused.render(at(0.6), brick, st, nullptr);
  const float* memory = first.image.px.data();
  const Rect drawn = first.active;
  reused.render(at(0.1), brick, st, nullptr);
  const BrickImages::Image& again = reused.render(at(-0.6), brick, st, nullptr);
  ASSERT_EQ(again.image.px.data(), memory) << "the first image's memory was recycled";
  const BrickImages::Image& want = fresh.render(at(-0.6), brick, st, nullptr);
  ASSERT_GT(drawn.area(), 0);
  ASSERT_GT(drawn.area() - intersect(drawn, want.active).area(), drawn.area() / 4)
      << "the first image drew where the last does not";
  EXPECT_EQ(again.active, want.active);
  EXPECT_TRUE(again.image == want.image);
}

}  // namespace
}  // namespace tessera::renderer

namespace tessera::renderer {
namespace {

// A frame's colour window re-renders the brick from the voxels held, equal to a caster made
// for the windowed map (cpu, shaded; osmesa), and back.
TEST(BrickImages, AFramesColourWindowRendersAsACasterOfTheWindowedMap) {
  for (BackendKind kind : {BackendKind::Cpu, BackendKind::Osmesa}) {
    SCOPED_TRACE(backendName(kind));
    Shell shell(32);
    shell.scene.shading.on = kind == BackendKind::Cpu;
    proto::SortLastWork work;
    const BrickBox brick{{0, 0, 0}, {32, 32, 32}};
    work.bricks.push_back({0, brick});
    BrickImages images(shell.scene, kind, 64, 1);
    proto::StageStats st;
    proto::FrameParams p = shell.p;
    p.window = {0.6, 0.3};
    images.hold(p, work, 0, st);
    const ImageF windowed_image = images.render(p, brick, st, nullptr).image;
    auto volume = std::make_shared<const Volume>(loadVolume(shell.scene));
    RenderOptions ro;
    ro.quality = p.quality;
    ro.threads = 1;
    auto fresh = [&](const ColorWindow& w) {
      return makeVolumeBackend(kind, volume, windowed(shell.scene.tf, w), shell.scene.shading)
          ->render(p.camera, p.width, p.height, brick, ro);
    };
    EXPECT_EQ(windowed_image.px, fresh(p.window).px);
    p.window = {};
    images.hold(p, work, 0, st);
    const ImageF plain = images.render(p, brick, st, nullptr).image;
    EXPECT_EQ(plain.px, fresh({}).px);
    EXPECT_NE(plain.px, windowed_image.px) << "the window changed nothing";
    EXPECT_EQ(st.images_made, 2u);
  }
}

}  // namespace
}  // namespace tessera::renderer
