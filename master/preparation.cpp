#include "master/preparation.h"

#include <algorithm>
#include <chrono>

#include <spdlog/spdlog.h>

#include "common/clock.h"
#include "common/scene_warnings.h"
#include "common/volume_summary.h"

namespace tessera::master {

namespace {
std::unique_ptr<Prepared> prepare(const MasterOptions& opt, const std::atomic<bool>* cancel) {
  auto out = std::make_unique<Prepared>();
  out->scene = opt.scene;
  VolumeSummary summary;
  if (!out->scene.mesh) {
    summary = summarizeVolume(out->scene, cancel);  // one pass over a file, which also finds a missing range
    for (const std::string& w : volumeWarnings(opt.scene, summary.shape)) spdlog::warn("{}", w);  // said once
    if (auto* raw = std::get_if<RawVolumeSpec>(&out->scene.volume)) {
      if (!raw->has_range) raw->has_range = true, raw->range = summary.shape.mapped_range;
      out->volume_range = raw->range;
    }
  }
  out->plan = makePlan(out->scene, opt.balance, opt.tiles_per_renderer, opt.binary_swap, std::move(summary));
  return out;
}
}  // namespace

Preparation::Preparation(const MasterOptions& opt)
    : reading_(std::async(std::launch::async, prepare, std::cref(opt), &cancel_)) {}

Preparation::~Preparation() {
  cancel_ = true;
  if (reading_.valid()) reading_.wait();
}

std::unique_ptr<Prepared> Preparation::await(const std::atomic<bool>* stop, const std::function<void()>& meanwhile) {
  const auto start = Clock::now();
  double next_note = 2;
  while (reading_.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
    meanwhile();
    if (stop && *stop) {
      cancel_ = true;
      return nullptr;
    }
    if (msSince(start) > next_note * 1000) {
      spdlog::info("reading the volume for its value range and block summary: {:.0f} s so far; stages wait for it",
                   msSince(start) / 1000);
      next_note += 10;
    }
  }
  try {
    return reading_.get();
  } catch (const std::exception& e) {
    throw ReadingFailed(e.what());
  }
}

bool HeldHellos::hold(const std::string& identity, const proto::Hello& hello) {
  auto it = held_.find(identity);
  if (it == held_.end()) {
    if (held_.size() >= kMost) return false;
    it = held_.emplace(identity, Held{Clock::now(), {}, {}}).first;
  }
  it->second.last = Clock::now(), it->second.hello = hello;
  return true;
}

std::vector<std::pair<std::string, proto::Hello>> HeldHellos::live(double silent_s) {
  std::vector<std::pair<Clock::time_point, std::pair<std::string, proto::Hello>>> live;
  for (const auto& [identity, h] : held_)
    if (msSince(h.last) < 1000 * silent_s) live.push_back({h.first, {identity, h.hello}});
  if (live.size() < held_.size())
    spdlog::info("{} stage(s) said Hello while the volume was read and fell silent since: not admitted",
                 held_.size() - live.size());
  held_.clear();
  std::sort(live.begin(), live.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::pair<std::string, proto::Hello>> out;
  for (auto& l : live) out.push_back(std::move(l.second));
  return out;
}

}  // namespace tessera::master
