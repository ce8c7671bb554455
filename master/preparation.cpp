#include "master/preparation.h"

#include <chrono>

#include <spdlog/spdlog.h>

#include "common/clock.h"
#include "common/volume_summary.h"

namespace tessera::master {

namespace {
std::unique_ptr<Prepared> prepare(const MasterOptions& opt) {
  auto out = std::make_unique<Prepared>();
  out->scene = opt.scene;
  if (out->scene.has_volume && !out->scene.mesh) {
    fixVolumeRange(out->scene);
    if (const auto* raw = std::get_if<RawVolumeSpec>(&out->scene.volume)) out->volume_range = raw->range;
  }
  out->plan = makePlan(out->scene, opt.balance, opt.tiles_per_renderer, opt.binary_swap);
  return out;
}
}  // namespace

Preparation::Preparation(const MasterOptions& opt) : reading_(std::async(std::launch::async, prepare, std::cref(opt))) {}

Preparation::~Preparation() {
  if (reading_.valid()) reading_.wait();
}

std::unique_ptr<Prepared> Preparation::await(const std::atomic<bool>* stop, const std::function<void()>& meanwhile) {
  const auto start = Clock::now();
  double next_note = 2;
  while (reading_.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
    meanwhile();
    if (stop && *stop) {
      spdlog::info("stopping once the volume's reading ends");
      return nullptr;
    }
    if (msSince(start) > next_note * 1000) {
      spdlog::info("reading the volume for its value range and block summary: {:.0f} s so far; stages wait for it",
                   msSince(start) / 1000);
      next_note += 10;
    }
  }
  return reading_.get();
}

}  // namespace tessera::master
