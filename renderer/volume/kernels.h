// Per-ray sampling kernels: the fast float path (SIMD over 8 consecutive samples of a ray,
// table classification, empty-space skipping, early termination) and the double-precision
// reference path. Both composite front to back into premultiplied RGBA. Thread-safe.
#pragma once
#include <cstdint>

#include "common/transfer_function.h"
#include "common/volume.h"
#include "renderer/volume/gradient.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/tf_table.h"
#include "renderer/volume/volume_accel.h"

namespace tessera::renderer {

struct SampleCounts {
  uint64_t taken = 0, skipped = 0, terminated = 0;
};

// Maximum intensity projection's skipping (max_kernel.cpp): per brick of VolumeAccel its
// largest 16-bit value (of its 9^3, apron included: all a sample in it reads), the volume's,
// and the floor below which nothing shows (MaxIntensity::floorQ). `complement`: the minimum
// projection, the maximum of 65535 - q (common/max_intensity.h); the values above are then the
// complement's (65535 less each brick's smallest value).
struct MaxSkip {
  const uint16_t* brick_max = nullptr;
  uint32_t volume_max = 65535, floor_q = 0;
  bool complement = false;
};
// At least VolumeAccel's 16-bit value of any voxel whose normalised value is at most `value`.
uint32_t quantizedUpperBound(float value);

struct FastContext {
  const Volume* volume = nullptr;
  const VolumeAccel* accel = nullptr;                     // quantized values, hierarchy
  const TfTable* table = nullptr;
  const MinMaxHierarchy::Emptiness* emptiness = nullptr;  // of `table`'s transfer function
  bool skip = true;                                       // empty-space skipping
  float early_termination = 2.0f;                        // > 1: never
  const ShadeParams* shade = nullptr;                     // null: unlit
  const GradientVolume* gradients = nullptr;              // of `volume`, with `shade`
  const HighlightTable* highlight = nullptr;              // of shade->shininess, with `shade`
  const uint64_t* occupancy = nullptr;                    // cellOccupancy of `emptiness` (null: none)
  const MaxSkip* maximum = nullptr;                       // blend: maximum (castMaximum)
};

// Samples span.k_first..k_end-1; out receives premultiplied RGBA. Returns true if the ray
// was terminated early (its opacity reached early_termination).
bool castFast(const FastContext& c, const RaySpan& span, float out[4], SampleCounts& counts);
// n rays, bit-identical to n castFast calls: the frame's constants are set up once, and the
// rays go two at a time, their empty-space decisions interleaved so the two dependency
// chains overlap in the CPU. terminated[i]: castFast's result for ray i.
void castFastBatch(const FastContext& c, const RaySpan* spans, float* const* out, int n, SampleCounts& counts,
                   bool* terminated);

// Maximum intensity projection (c.maximum set): the ray's value pixel (common/max_intensity.h), its
// largest value in 16-bit units / 65535 (with c.maximum->complement: of 65535 - q, the minimum
// projection), or transparent when none reaches the floor. With
// c.skip, samples in bricks that cannot raise the maximum are passed over (counted as skipped);
// once the volume's largest value is reached the rest count as terminated. Returns false.
bool castMaximum(const FastContext& c, const RaySpan& span, float out[4], SampleCounts& counts);
// The same in double precision on the volume's values, with every sample: `floor` in [0, 1].
// `complement`: the largest 1 - value (the minimum projection).
void castReferenceMaximum(const Volume& v, double floor, bool complement, const RaySpan& span, double out[4],
                          SampleCounts& counts);

// Double precision, exact transfer function, no skipping, no early termination; `shade`
// (null: unlit) lights each sample with its exact gradient (sampleGradient).
void castReference(const Volume& v, const TransferFunction& tf, double step, const ShadeParams* shade,
                   const RaySpan& span, double out[4], SampleCounts& counts);

// Lower corner index i and weight f of coordinate u on an axis of n voxels, clamped so both
// corners exist (the reference path's sampleTrilinear and sampleGradient share it).
void trilinearCorner(double u, int n, int& i, double& f);

// Trilinear interpolation at voxel coordinate u (voxel centres at integers), clamped at
// the border; double precision (the reference path and tests use it).
double sampleTrilinear(const Volume& v, double ux, double uy, double uz);

}  // namespace tessera::renderer
