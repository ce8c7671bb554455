// Isosurface of a Volume by marching cubes: vertices on the grid of voxel centres in the
// volume's world box (common/volume.h), normals from the central-difference gradient
// (pointing towards lower values), colour `color`. Pure function; thread-safe.
#pragma once
#include <array>
#include <functional>

#include "common/volume.h"
#include "renderer/mesh/mesh.h"

namespace tessera::renderer {

// Triangles separate voxels with value >= level from those below. An empty result (level
// outside the data) is an empty Mesh, not an error; the caller decides.
Mesh marchingCubes(const Volume& volume, float level,
                   std::array<float, 3> color = {kDefaultMeshColor[0], kDefaultMeshColor[1], kDefaultMeshColor[2]});
// The same mesh, bit for bit, from a volume of `dims` read as z-slabs of `layers` cube layers
// (plus 3 planes kept from the slab before): `load(box)` returns the window `box` (whole x-y
// planes; each box starts where the last ended), so memory holds one slab, never the volume.
Mesh marchingCubes(const std::array<int, 3>& dims, const std::function<Volume(const VoxelBox&)>& load, float level,
                   int layers, std::array<float, 3> color = {kDefaultMeshColor[0], kDefaultMeshColor[1], kDefaultMeshColor[2]});

}  // namespace tessera::renderer
