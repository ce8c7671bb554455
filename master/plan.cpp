#include "master/plan.h"

#include "master/sort_first_plan.h"
#include "master/sort_last_plan.h"

namespace tessera::master {

std::unique_ptr<Plan> makePlan(const Scene& scene, bool balance, int tiles_per_renderer, bool binary_swap,
                               VolumeSummary volume) {
  if (scene.mesh) return std::make_unique<SortFirstPlan>(balance, tiles_per_renderer);
  // The bricks hold equal shares of what the first frames show: the map through the scene's window.
  return std::make_unique<SortLastPlan>(std::move(volume), windowed(scene.tf, colorWindow(scene)), balance, binary_swap,
                                        scene.crop);
}

}  // namespace tessera::master
