// Streaming summary of a volume (see volume_summary.h).
#include "common/volume_summary.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "common/bricks.h"

namespace tessera {

namespace {
// The range a file without one is mapped with: its values' min..max. Constant data (one
// value c): [c, c + 1], which maps every voxel to 0 as normalising with [c, c] does.
std::array<double, 2> rangeOfValues(double lo, double hi) { return {lo, hi > lo ? hi : lo + 1}; }
}  // namespace

std::array<double, 2> fixVolumeRange(Scene& scene) {
  const Volume probe = loadVolume(scene, VoxelBox{{0, 0, 0}, {1, 1, 1}});
  if (auto* raw = std::get_if<RawVolumeSpec>(&scene.volume); raw && !raw->has_range) {
    raw->has_range = true;
    raw->range = rangeOfValues(probe.mapped_range[0], probe.mapped_range[1]);
  }
  return probe.data_range;
}

VolumeSummary summarizeVolume(const Scene& scene, const std::atomic<bool>* cancel) {
  // A file without `range` is read once, in its own values: the blocks' bounds are normalised
  // at the end with the range found on the way (normalising is monotonic, so they are the
  // bounds of the normalised values the renderers will hold), not after a scan of its own.
  const auto* declared = std::get_if<RawVolumeSpec>(&scene.volume);
  std::optional<RawVolumeReader> values;
  std::optional<VolumeReader> mapped;
  if (!declared || declared->has_range) mapped.emplace(scene);  // one pass over the file (a gzip stream decoded once)
  // Errors name the scene and its volume, as VolumeReader's do.
  auto readSlab = [&](const VoxelBox& box) -> Volume {
    if (mapped) return mapped->read(box);
    try {
      if (!values) values.emplace(std::get<RawVolumeSpec>(stepVolume(scene, 0)));
      return values->readValues(box);
    } catch (const SceneError&) {
      throw;
    } catch (const std::exception& e) {
      throw SceneError((scene.path.empty() ? "<default scene>" : scene.path) + ": volume: " + e.what());
    }
  };
  VolumeSummary s;
  const std::array<int, 3> n = volumeDims(scene);
  // At least 8^3 blocks to split into bricks (a small volume gets smaller blocks), but a thin
  // axis (a few slices) must not shrink every block to a voxel (8192 x 8192 x 4: 2 GiB).
  auto blocks = [&](int e) { return (long long)((n[0] + e - 1) / e) * ((n[1] + e - 1) / e) * ((n[2] + e - 1) / e); };
  while (s.edge > 1 && blocks(s.edge) < 512) s.edge /= 2;
  for (int a = 0; a < 3; ++a) s.blocks[a] = (n[a] + s.edge - 1) / s.edge;
  const size_t count = (size_t)s.blocks[0] * s.blocks[1] * s.blocks[2];
  s.lo.assign(count, INFINITY);
  s.hi.assign(count, -INFINITY);
  std::array<double, 2> data{INFINITY, -INFINITY};
  double offset = 0;  // the slabs' values hold value - offset (readValues)
  for (int z0 = 0; z0 < n[2]; z0 += s.edge) {
    if (cancel && *cancel) throw std::runtime_error("the volume's summary was cancelled");
    const VoxelBox box{{0, 0, z0}, {n[0], n[1], std::min(n[2], z0 + s.edge)}};
    const Volume slab = readSlab(box);
    s.shape.spacing = slab.spacing;
    s.shape.mapped_range = slab.mapped_range;  // every slab's: the range is the scene's
    offset = slab.value_offset;  // every slab's: one reader
    data[0] = std::min(data[0], slab.data_range[0]);
    data[1] = std::max(data[1], slab.data_range[1]);
    const size_t row = (size_t)s.blocks[0] * s.blocks[1] * (z0 / s.edge);
    for (int z = 0; z < slab.dims[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const size_t b = row + x / s.edge + (size_t)s.blocks[0] * (y / s.edge);
          const float v = slab.at(x, y, z);
          s.lo[b] = std::min(s.lo[b], v);
          s.hi[b] = std::max(s.hi[b], v);
        }
  }
  if (!mapped) {  // as fixVolumeRange fixes it
    const auto [lo, hi] = rangeOfValues(data[0], data[1]);
    for (size_t b = 0; b < count; ++b)
      s.lo[b] = normaliseSample(s.lo[b], lo - offset, hi - offset), s.hi[b] = normaliseSample(s.hi[b], lo - offset, hi - offset);
    s.shape.mapped_range = {lo, hi};
  }
  s.shape.dims = n;
  s.shape.data_range = data;  // the slabs' own values: the whole volume's
  return s;
}

std::vector<uint8_t> visibleBlocks(const VolumeSummary& s, const TransferFunction& tf, const Crop& crop) {
  std::vector<uint8_t> mask(s.lo.size());
  for (size_t i = 0; i < mask.size(); ++i) mask[i] = tf.maxAlpha(s.lo[i], s.hi[i]) > 0;
  if (crop.whole()) return mask;
  const VoxelBox box = cropBox(crop, s.shape.dims);
  const auto& [bx, by, bz] = s.blocks;
  for (int z = 0; z < bz; ++z)
    for (int y = 0; y < by; ++y)
      for (int x = 0; x < bx; ++x) {
        const int b[3] = {x, y, z};
        bool inside = true;  // the block [b * edge, (b + 1) * edge) meets the crop box
        for (int a = 0; a < 3; ++a) inside = inside && (b[a] + 1) * s.edge > box.lo[a] && b[a] * s.edge < box.hi[a];
        if (!inside) mask[x + (size_t)bx * (y + (size_t)by * z)] = 0;
      }
  return mask;
}

BrickTree splitBricks(const VolumeSummary& s, int n, const TransferFunction& tf, const Crop& crop) {
  const std::vector<uint8_t> mask = visibleBlocks(s, tf, crop);
  return scaleBricks(splitMask(s.blocks, &mask, n), s.edge, s.shape.dims);
}

}  // namespace tessera
