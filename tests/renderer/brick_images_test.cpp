// What a volume renderer holds and renders (renderer/brick_images.h): a frame whose inputs
// did not change reuses its image, and the image a binary swap's rounds still read is never
// recycled while the next frame renders (its memory and pixels stay as they were).
#include <gtest/gtest.h>

#include <vector>

#include "common/volume_summary.h"
#include "renderer/brick_images.h"

namespace tessera::renderer {
namespace {

TEST(BrickImages, AnUnchangedFrameIsReusedAndTheImageInTheRoundsIsNeverRecycled) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 32, 1, {1, 1, 1}};
  fixVolumeRange(scene);
  BrickImages images(scene, BackendKind::Cpu, 64, 1);
  proto::FrameParams p;
  p.width = p.height = 24;
  p.camera = scene.camera;
  p.quality = scene.quality;
  proto::SortLastWork work;
  const BrickBox brick{{0, 0, 0}, {32, 32, 32}};
  work.bricks.push_back({0, brick});
  proto::StageStats st;
  images.hold(p, work, 0, st);
  auto at = [&](double x) {
    proto::FrameParams q = p;
    q.camera.eye[0] += x;
    return q;
  };

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

}  // namespace
}  // namespace tessera::renderer
