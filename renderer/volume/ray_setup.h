// Per-ray setup shared by all kernels: the global sample grid along a ray and the part of
// it that belongs to one brick. Double precision; plain functions, thread-safe.
#pragma once
#include <array>
#include <cstdint>
#include <limits>

#include "common/bricks.h"
#include "common/camera.h"
#include "common/image.h"
#include "common/volume.h"

namespace tessera::renderer {

// World <-> voxel mapping of one volume (docs/DESIGN.md: origin-centred box, largest extent 1,
// voxel i at the centre of its cell). Voxel indices are the held values' (a window's own,
// from 0); `origin` places them in the whole volume, which alone sets the world box.
struct VolumeGeometry {
  std::array<int, 3> origin{0, 0, 0};         // of the held voxels in the whole volume
  std::array<int, 3> whole{1, 1, 1};          // the whole volume's dims
  std::array<double, 3> half{0.5, 0.5, 0.5};  // half extents of the whole box (world)
  std::array<double, 3> cell{1, 1, 1};        // cell edge (world)

  explicit VolumeGeometry(const Volume& v);
  // World coordinate of the cell boundary q on an axis (q = -origin..whole-origin). Every
  // box (whole volume or brick, in any window) uses this one expression on the whole
  // volume's index, so shared faces give bit-identical ray parameters.
  double plane(int axis, int q) const { return -half[axis] + (q + origin[axis]) * cell[axis]; }
  // The whole volume's box in held-voxel indices (the start of every ray's sample grid).
  BrickBox wholeBox() const {
    return {{-origin[0], -origin[1], -origin[2]}, {whole[0] - origin[0], whole[1] - origin[1], whole[2] - origin[2]}};
  }
};

// The samples of one ray inside one brick. Sample k sits at t_k = t0 + (k + offset) * step,
// t0 = max(0, entry into the WHOLE volume), so every brick shares one grid along the ray;
// a brick takes exactly the k with t_k in [t_in, t_out) of its own box. The offset is 0.5
// (mid-step), or the pixel's own with `quality.jitter` (pixelJitter): a function of the pixel
// alone, so every brick still shares the ray's grid.
// In voxel coordinates (voxel centres at integers) sample k is at u0 + k * du.
struct RaySpan {
  double t0 = 0;
  double offset = 0.5;
  int64_t k_first = 0, k_end = 0;  // samples [k_first, k_end); empty if equal
  std::array<double, 3> u0{}, du{};
  bool empty() const { return k_end <= k_first; }
};

// Half-open ray-box interval [t_in, t_out) over the voxel box [lo, hi): a point belongs
// to the box iff plane(lo) <= x < plane(hi) per axis (in ray parameter form). Adjacent
// boxes therefore partition every ray exactly. Returns false if the interval is empty.
bool boxInterval(const VolumeGeometry& g, const Ray& r, const BrickBox& b, double& t_in, double& t_out);

// Where in its step pixel (px, py)'s samples sit with `quality.jitter`, in [0, 1): a
// dither in integer arithmetic, so every process and instruction set computes the same bits.
// Neighbouring pixels get offsets spread over the step, so the rings an unjittered grid draws
// on opaque surfaces (wood grain) become fine noise.
double pixelJitter(int px, int py);
// pixelJitter of pixels (px0 + i, py), i < kSpanLanes (raySpans' lanes).
void rowJitter(int px0, int py, double* offsets);

// Computes the span of `brick` on the global grid of `step` with samples at `offset` within
// their step (0.5, or pixelJitter). Returns false if empty.
bool raySpan(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, double step, RaySpan& span,
             double offset = 0.5);

// The same span cut to `clip` (a box inside `brick`, e.g. the part of the volume that can
// be non-empty) and to the ray parameters [t_lo, t_hi) (e.g. the depths of non-empty
// nodes): the sample grid is unchanged, only k_first/k_end narrow. With `before` and
// `after`, they receive how many of the brick's samples lie before / after the cut span
// (all of them in `before` if it is empty); without, the brick's own range is not computed.
bool raySpanClipped(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, const BrickBox& clip, double step,
                    RaySpan& span, int64_t* before = nullptr, int64_t* after = nullptr,
                    double t_lo = -std::numeric_limits<double>::infinity(),
                    double t_hi = std::numeric_limits<double>::infinity(), double offset = 0.5);

// The constants of raySpans for one frame and brick: the camera's basis, and the planes of
// the whole volume's, the brick's and the clip's boxes (VolumeGeometry::plane); `jitter`:
// each pixel's samples at pixelJitter, else mid-step.
struct SpanRow {
  SpanRow(const RayGenerator& gen, const VolumeGeometry& g, const BrickBox& brick, const BrickBox& clip, double step,
          bool jitter);
  RayGenerator::Basis basis;
  double half[3], cell[3], origin[3];
  double whole_lo[3], whole_hi[3], brick_lo[3], brick_hi[3], clip_lo[3], clip_hi[3];
  bool brick_is_whole, clip_is_brick, jitter;
  double step, inv_step;
};
inline constexpr int kSpanLanes = 8;
// The spans of pixels (px0 + i, py), i < n <= kSpanLanes, several rays at a time (SIMD
// where the CPU has it): bit for bit raySpanClipped(pixelRay(px0 + i, py), brick, clip,
// step, span, nullptr, nullptr, t_lo[i], t_hi[i], offset) with the pixel's offset. t_lo and t_hi hold kSpanLanes values
// (the lanes past n are computed and dropped). Bit i of the result: pixel i's ray has
// samples (spans[i] means something only then).
unsigned raySpans(const SpanRow& row, int px0, int py, int n, const double* t_lo, const double* t_hi, RaySpan* spans);

// How many samples of the global grid of `step` lie in `brick` (raySpan's k_end - k_first,
// without the sample positions).
int64_t spanSamples(const VolumeGeometry& g, const Ray& r, const BrickBox& brick, double step, double offset);

// Pixels whose centre ray can hit the brick, shared by both volume backends so they touch
// the same pixels: the bounding box of its projected corners plus one pixel; the whole
// image if a corner is behind the eye (the projection is not convex then).
Rect brickFootprint(const RayGenerator& gen, const VolumeGeometry& g, const BrickBox& b, int w, int h);

}  // namespace tessera::renderer
