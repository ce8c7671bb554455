// How a frame's work is dealt to the alive stages; one plan per mode (sort_last_plan.h:
// bricks + compositor bands; sort_first_plan.h: screen tiles). Plans learn from the
// stages' Stats (active pixels, tile costs) to balance the next frames.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/scene.h"
#include "common/volume_summary.h"
#include "common/wire/protocol.h"

namespace tessera::master {

struct CompositorSlot {
  uint32_t rank = 0;
  std::string endpoint;
};

struct Workers {
  std::vector<uint32_t> renderers;           // ranks, ascending
  std::vector<CompositorSlot> compositors;   // by rank
  std::vector<std::string> renderer_endpoints = {};  // per renderer: where it takes binary-swap pieces
};

class Plan {
 public:
  virtual ~Plan() = default;
  // The alive stages changed (also called once before the first frame).
  virtual void reassign(const Workers& w) = 0;
  // Fills p's work (bricks/order or tiles, and regions) for p.frame and p.camera.
  virtual void fill(proto::FrameParams& p, const Workers& w) = 0;
  // A renderer's accepted Stats.
  virtual void stats(const proto::StageStats& s, const Workers& w) = 0;
  // Whether frames need a compositor (a binary-swap farm's renderers send the display its bands).
  virtual bool needsCompositors(const Workers&) const { return true; }
  // Whether frames can be issued to these stages (a binary-swap farm runs with no compositor).
  bool canRun(const Workers& w) const { return !w.renderers.empty() && (!w.compositors.empty() || !needsCompositors(w)); }
};

// The scene's plan: sort-first for a mesh (the master needs no volume: renderers own the
// mesh; `volume` unused), else sort-last from the volume's summary.
std::unique_ptr<Plan> makePlan(const Scene& scene, bool balance, int tiles_per_renderer, bool binary_swap,
                               VolumeSummary volume);

}  // namespace tessera::master
