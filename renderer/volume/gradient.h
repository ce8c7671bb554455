// Gradients for shading (docs/DESIGN.md): at voxel i, G(i) = (v[i+1] - v[i-1]) / 2 per axis in
// normalised value per voxel, one-sided (v[i+1] - v[i] or v[i] - v[i-1]) at the faces of the
// held voxels; at a sample, G is interpolated with the sample's trilinear weights. Away from
// the faces that is exactly the central difference of the trilinear field one voxel either
// side of the sample. A renderer holds two ghost voxels around its bricks, so its samples never
// read a face of its window that is not a face of the whole volume: bricks shade exactly as
// the whole volume does.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "common/scene.h"
#include "common/volume.h"

namespace tessera::renderer {

// Trilinear G at voxel coordinate u (voxel centres at integers, clamped like
// sampleTrilinear); double precision (the reference path).
void sampleGradient(const Volume& v, double ux, double uy, double uz, double g[3]);

// G of every held voxel, 4 int16 per voxel (x, y, z, 0) in the values' order, each component
// round(G * kScale): a voxel's gradient is one 64-bit read. 8 bytes per voxel.
struct GradientVolume {
  static constexpr float kScale = 32767.0f;
  explicit GradientVolume(const Volume& v);
  std::vector<int16_t> q;
};

// A gradient whose every component is below half a quantization step (|G| < 2^-16 of the value
// range per voxel) has no direction: both kernels light such a sample with ambient + diffuse
// and no highlight, as an unlit transfer function would show it, dimmed by nothing.
inline constexpr double kFlatGradient = 0.5 / GradientVolume::kScale;

// One frame's lighting, shared by both kernels: the scene's coefficients, the light's world
// direction (zero: a headlight) and the world edge of a voxel cell, which turns gradients in
// voxel units into world directions.
struct ShadeParams {
  double ambient = 0, diffuse = 0, specular = 0, shininess = 1;
  std::array<double, 3> light{0, 0, 0};
  std::array<double, 3> cell{1, 1, 1};
};
ShadeParams shadeParams(const Shading& s, const Vec3& light, const std::array<double, 3>& cell);

// The light and halfway directions of one ray in voxel-gradient terms: for a voxel-unit
// gradient G, N.L = (G * inv_cell).l / |G * inv_cell|. `du` is the ray's step in voxel units.
struct RayLight {
  double inv_cell[3], l[3], h[3];
};
RayLight rayLight(const ShadeParams& p, const std::array<double, 3>& du);

// x^shininess for the fast kernels, sampled at kEntries points of [0, 1] and linearly
// interpolated: no pow per sample, error below 1.2e-4 for any shininess up to 128
// (n (n - 1) / 8 / (kEntries - 1)^2 bounds it).
struct HighlightTable {
  static constexpr int kEntries = 4096;
  explicit HighlightTable(double shininess);
  std::vector<float> values;  // kEntries + 1 (the last repeats 1 for the interpolation)
};

}  // namespace tessera::renderer
