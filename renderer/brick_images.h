// What a volume renderer holds and renders: the voxels of its bricks and their ghost layer for
// a frame's step (from the step cache, or loaded then), and its last two brick images, reused
// when a frame's inputs did not change (a static view is rendered once). Memory follows the
// bricks, not the volume.
#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "common/scene.h"
#include "common/wire/protocol.h"
#include "renderer/step_cache.h"

namespace tessera::renderer {

class BrickImages {
 public:
  // `scene` must outlive this; its volume range is fixed before the first load (the renderer
  // takes the master's, see Stage::fixRange).
  BrickImages(const Scene& scene, BackendKind backend, int cache_mb, int threads);

  struct Image {
    // What determines a brick's image: a frame with the same key is not rendered again.
    struct Key {
      Camera camera;
      Quality quality;
      int width = 0, height = 0;
      BrickBox brick;
      int step = 0;
      ColorWindow window;
      bool operator==(const Key&) const = default;
    };
    Key key;
    ImageF image;
    Rect active;
  };

  // Holds the window of `rank`'s bricks in `work` for frame p's step; a move of bricks or a
  // step not prefetched costs a load, in st. Throws when the step cannot be read and no
  // earlier step is held.
  void hold(const proto::FrameParams& p, const proto::SortLastWork& work, uint32_t rank, proto::StageStats& st);
  // The image of `brick` (held) for frame p; `in_rounds`, an image a binary swap's rounds
  // still read, is not recycled. A binary-swap frame renders on the renderer's worker thread
  // while the stage thread plays the rounds of the frame before: hold() and render() are
  // called by one thread at a time, and images stay where they are until recycled.
  const Image& render(const proto::FrameParams& p, const BrickBox& brick, proto::StageStats& st, const Image* in_rounds);

  // The steps the frames after the first of `queued` will show: read them ahead.
  void prefetch(const std::deque<proto::FrameParams>& queued);
  void logSteps();  // a time series: what the step cache did over the run

 private:
  const Scene& scene_;
  int cache_mb_, threads_;
  StepCache steps_;
  HeldStep held_;             // the window and caster of the frame being rendered
  std::deque<Image> images_;  // the last two (a renderer may own two bricks after a failure)
};

}  // namespace tessera::renderer
