// What a scene will show badly, said before anything renders: each warning names the scene
// and the key to change, and what to do. The master logs them once, tessera-render and
// tessera-info print them.
#pragma once
#include <string>
#include <vector>

#include "common/scene.h"
#include "common/value_histogram.h"
#include "common/volume.h"

namespace tessera {

// `shape`: the volume's dims, spacing, data range and mapped range (no values needed).
// Warns of a range that misses the data (rangeProblem), of a `window` beside every value the
// range leaves the voxels or narrower than the casters resolve, and of a volume so thin that
// the transfer function's opacity cannot show it.
std::vector<std::string> volumeWarnings(const Scene& scene, const Volume& shape);

// "" unless the scene gives neither `range` nor `window` for a file whose values suggest one (suggestedRange
// over `fine`, the data's histogram): then what lies apart and the `range` to give.
std::string rangeSuggestion(const Scene& scene, const ValueHistogram& fine);

}  // namespace tessera
