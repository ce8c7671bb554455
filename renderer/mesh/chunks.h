// Sort-first geometry grouping: a mesh's triangles reordered into spatially coherent chunks
// (Morton order of centroids) with object-space bounding boxes, and each chunk's conservative
// screen rectangle so that a tile draws only the chunks that can touch it. Plain values.
#pragma once
#include <cstdint>
#include <vector>

#include "common/image.h"
#include "renderer/mesh/mesh.h"
#include "renderer/gl/projection.h"

namespace tessera::renderer {

struct Chunk {
  uint32_t first_triangle = 0, triangle_count = 0;
  Box box;  // object-space bounds of its triangles
};

// Reorders mesh.indices (triangles, not vertices) in Morton order of their centroids and cuts
// them into consecutive chunks of triangles_per_chunk (the last may be smaller). >= 1 chunk for
// a non-empty mesh. Throws std::invalid_argument if triangles_per_chunk == 0.
std::vector<Chunk> buildChunks(Mesh& mesh, uint32_t triangles_per_chunk);

// Pixels (top-left origin, clipped to the image) that the box's projection can cover, with a
// one-pixel margin against rounding; the whole image if the box crosses the eye plane, empty if
// it is wholly behind the near plane or off screen.
Rect screenRect(const Box& box, const ViewProjection& vp);

// Indices of the chunks whose screen rectangle intersects tile, in chunk order.
std::vector<int> chunksInTile(const std::vector<Chunk>& chunks, const ViewProjection& vp, const Rect& tile);

}  // namespace tessera::renderer
