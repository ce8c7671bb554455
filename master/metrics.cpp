#include "master/metrics.h"

#include <algorithm>
#include <set>
#include <filesystem>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "master/balance.h"

namespace tessera::master {

Metrics::Metrics(const std::string& path, uint64_t total_frames)
    : interactive_run_(total_frames == 0), start_(std::chrono::steady_clock::now()), run_(total_frames, start_) {
  if (path.empty()) return;
  auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir);
  // Checked now, truncated only at the first line: a run that fails to start keeps the
  // previous run's metrics.
  existed_ = std::filesystem::exists(path);
  if (!std::ofstream(path, std::ios::app)) throw std::runtime_error("cannot write metrics file " + path);
  path_ = path;
}

Metrics::~Metrics() {
  if (path_.empty() || wrote_ || existed_) return;
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);  // the empty file this run created
}

void Metrics::issued(uint64_t frame, uint32_t epoch, int renderers, int compositors, const FrameSpec& spec) {
  Frame& f = frames_[frame];
  f = Frame{};  // a frame issued again under a new epoch starts over
  f.epoch = epoch;
  f.renderers = renderers;
  f.compositors = compositors;
  f.spec = spec;
}

void Metrics::cancelled(uint64_t frame) {
  if (frames_.erase(frame)) ++cancelled_;
}

void Metrics::stats(const proto::StageStats& s) {
  auto it = frames_.find(s.frame);
  if (it == frames_.end()) return;  // written already
  if (s.epoch != it->second.epoch) return;  // for an earlier issue of the frame
  // One report per stage and frame: a repeated one replaces the first, so that no member can
  // grow the master's memory by repeating its Stats.
  auto& reports = s.role == proto::Role::Renderer ? it->second.r : it->second.c;
  auto same = std::find_if(reports.begin(), reports.end(), [&](const proto::StageStats& r) { return r.rank == s.rank; });
  if (same != reports.end()) *same = s;
  else reports.push_back(s);
  if (it->second.done && (int)it->second.r.size() >= it->second.renderers &&
      (int)it->second.c.size() >= it->second.compositors)
    write(it->first, it->second), frames_.erase(it);
}

void Metrics::done(const proto::FrameDone& d, double latency_ms, uint64_t master_dropped) {
  Frame& f = frames_[d.frame];
  f.done = true;
  f.d = d;
  f.latency_ms = latency_ms;
  f.master_dropped = master_dropped;
  f.done_at = std::chrono::steady_clock::now();
  if ((int)f.r.size() >= f.renderers && (int)f.c.size() >= f.compositors) write(d.frame, f), frames_.erase(d.frame);
}

void Metrics::flushOlderThan(std::chrono::steady_clock::time_point t) {
  for (auto it = frames_.begin(); it != frames_.end();) {
    if (it->second.done && it->second.done_at < t) {
      write(it->first, it->second);
      it = frames_.erase(it);
    } else {
      ++it;
    }
  }
}

void Metrics::flushAll() { flushOlderThan(std::chrono::steady_clock::time_point::max()); }

nlohmann::json Metrics::summarize(const std::vector<proto::StageStats>& renderers,
                                  const std::vector<proto::StageStats>& compositors, const proto::FrameDone& done,
                                  double latency_ms) {
  auto stage = [](const std::vector<proto::StageStats>& v, nlohmann::json& j, const char* prefix) {
    std::vector<double> work, active;
    double enc = 0, dropped = 0;
    uint64_t raw = 0, encoded = 0, px = 0;
    for (const auto& s : v) {
      work.push_back(s.work_ms);
      active.push_back((double)s.active_pixels);
      enc = std::max(enc, s.encode_ms);
      raw += s.bytes_raw;
      encoded += s.bytes_encoded;
      px += s.active_pixels;
      dropped += (double)s.dropped;
    }
    std::string p = prefix;
    j[p + "_ms_max"] = work.empty() ? 0 : *std::max_element(work.begin(), work.end());
    j[p + "_encode_ms_max"] = enc;
    j[p + "_bytes_raw"] = raw;
    j[p + "_bytes_encoded"] = encoded;
    j[p + "_active_pixels"] = px;
    j[p + "_imbalance_time"] = imbalance(work);
    j[p + "_imbalance_pixels"] = imbalance(active);
    j[p + "_dropped"] = dropped;
    j[p + "_reports"] = v.size();
  };
  nlohmann::json j;
  j["frame"] = done.frame;
  j["latency_ms"] = latency_ms;
  stage(renderers, j, "render");
  stage(compositors, j, "composite");
  // A frame whose every image was reused (the camera did not move) was not rendered: it
  // says so instead of a render time of a few microseconds.
  uint64_t made = 0, reused = 0;
  double load = 0;
  for (const auto& s : renderers) made += s.images_made, reused += s.images_reused, load = std::max(load, s.load_ms);
  if (load > 0) j["render_load_ms_max"] = load;  // only frames where a renderer loaded voxels
  j["render_images_made"] = made;
  j["render_images_reused"] = reused;
  const bool rerendered = made > 0 || reused == 0;
  j["rerendered"] = rerendered;
  if (!rerendered) j.erase("render_ms_max"), j.erase("render_imbalance_time");
  double decode = 0, swap = 0, wait = 0;  // compositors decode what they receive; renderers, binary-swap pieces
  for (const auto& s : compositors) decode = std::max(decode, s.decode_ms);
  for (const auto& s : renderers) swap = std::max(swap, s.decode_ms), wait = std::max(wait, s.wait_ms);
  j["composite_decode_ms_max"] = decode;
  if (swap > 0) {  // only frames composited by binary swap
    j["render_swap_ms_max"] = swap;
    j["render_swap_wait_ms_max"] = wait;
  }
  // Sort-first: chunk-tile pairs drawn per chunk (WireGL's overlap factor) and triangles.
  double drawn = 0, chunks = 0, triangles = 0;
  for (const auto& s : renderers) {
    drawn += (double)s.chunks_drawn;
    chunks = std::max(chunks, (double)s.chunks_total);
    triangles += (double)s.triangles;
  }
  // A time series: each renderer's step cache (cumulative hits and misses, bytes read and
  // prefetch time since its last frame).
  uint64_t hits = 0, misses = 0, read = 0;
  double prefetch = 0;
  for (const auto& s : renderers)
    hits += s.step_hits, misses += s.step_misses, read += s.bytes_read, prefetch = std::max(prefetch, s.prefetch_ms);
  if (hits + misses > 0) {
    j["render_step_hits"] = hits;
    j["render_step_misses"] = misses;
    j["render_bytes_read"] = read;
    j["render_prefetch_ms_max"] = prefetch;
    // Each renderer's cache by rank: which one reads slowly or misses is seen, not averaged away.
    std::vector<const proto::StageStats*> by_rank;
    for (const auto& s : renderers) by_rank.push_back(&s);
    std::sort(by_rank.begin(), by_rank.end(), [](auto* a, auto* b) { return a->rank < b->rank; });
    auto& per = j["render_step_cache"] = nlohmann::json::array();
    for (const auto* s : by_rank)
      per.push_back({{"rank", s->rank}, {"hits", s->step_hits}, {"misses", s->step_misses}, {"bytes_read", s->bytes_read},
                     {"load_ms", s->load_ms}, {"prefetch_ms", s->prefetch_ms}});
  }
  if (chunks > 0) {  // only geometry frames have them
    j["overlap_factor"] = drawn / chunks;
    j["triangles"] = triangles;
  }
  j["display_ms"] = done.display_ms;
  j["route_ms"] = done.route_ms;
  j["display_bytes_encoded"] = done.bytes_encoded;
  j["strips_rejected"] = done.strips_rejected;
  j["display_dropped"] = done.dropped;
  return j;
}

void Metrics::write(uint64_t frame, Frame& f) {
  ++frames_done_;
  auto j = summarize(f.r, f.c, f.d, f.latency_ms);
  j["frame"] = frame;
  j["epoch"] = f.epoch;
  // The step the renderers showed: a step that could not be read shows the last good one in
  // its place (it was reported as the step asked for: found by review).
  std::set<uint32_t> shown;
  for (const auto& s : f.r)
    if (s.images_made + s.images_reused > 0) shown.insert(s.step);  // a renderer without a brick shows none
  j["step"] = shown.size() == 1 ? *shown.begin() : f.spec.step;
  if (shown.size() > 1 || (shown.size() == 1 && (int)*shown.begin() != f.spec.step)) j["step_asked"] = f.spec.step;
  if (shown.size() > 1) {  // renderers showed different steps: a mixed frame
    j["steps_shown"] = shown;
    mixed_.push_back({frame, f.spec.step, shown});
  }
  j["master_dropped"] = f.master_dropped;
  j["reassignments"] = reassignments_;
  j["reissued_frames"] = reissued_;
  j["refused_peers"] = refused_;
  // When FrameDone arrived, from the first frame's: throughput = frames / span.
  j["done_ms"] = std::chrono::duration<double, std::milli>(f.done_at - start_).count();
  if (interactive_run_) {
    const Camera& c = f.spec.camera;
    j["interactive"] = f.spec.interactive;
    j["width"] = f.spec.width;
    j["height"] = f.spec.height;
    j["camera"] = {{"eye", {c.eye.x, c.eye.y, c.eye.z}}, {"target", {c.target.x, c.target.y, c.target.z}},
                   {"up", {c.up.x, c.up.y, c.up.z}}, {"fov", c.fov}};
    j["window"] = {f.spec.window.center, f.spec.window.width};
    if (f.d.input_ms > 0) j["input_ms"] = f.d.input_ms;
    j["cancelled_frames"] = cancelled_;
  }
  spdlog::debug("frame={} latency_ms={:.1f} render_ms={:.1f} composite_ms={:.1f} display_ms={:.1f} bytes_raw={} "
               "bytes_encoded={} render_imbalance={:.2f} composite_imbalance={:.2f}",
               frame, f.latency_ms, j.value("render_ms_max", 0.0), j["composite_ms_max"].get<double>(),
               f.d.display_ms, j["render_bytes_raw"].get<uint64_t>(), j["render_bytes_encoded"].get<uint64_t>(),
               j.value("render_imbalance_time", 0.0), j["composite_imbalance_pixels"].get<double>());
  if (!path_.empty() && !out_.is_open()) out_.open(path_, std::ios::trunc);
  if (out_.is_open() && out_) out_ << j.dump() << '\n' << std::flush;
  wrote_ = wrote_ || (out_.is_open() && out_);
  // Nothing visible: the compositors blended or routed no pixel, or in a binary-swap frame
  // (no compositor takes part) no renderer's brick image has one.
  const bool empty = f.compositors > 0
                         ? j["composite_reports"].get<size_t>() > 0 && j["composite_active_pixels"].get<double>() == 0
                         : j["render_reports"].get<size_t>() > 0 && j["render_active_pixels"].get<double>() == 0;
  if (!warned_empty_ && empty) {
    warned_empty_ = true;  // once a run: an empty frame is usually the scene, not the farm
    spdlog::warn("frame {} has no visible pixel: is the camera looking at the volume, and does the transfer "
                 "function give the data's values any opacity? (tessera-info SCENE shows the values, the "
                 "range they are mapped from and the full scene)",
                 frame);
  }
  if (auto progress = run_.add(j, f.done_at)) spdlog::info("{}", *progress);
}

}  // namespace tessera::master
