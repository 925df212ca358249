// One coarsening pass among vertices the caller chose (not installed): the
// distributed coarsen (distributed.cpp) runs the serial pass on each part,
// among the vertices the whole mesh's pass would consider that no other
// part holds.
#pragma once

#include "bisect/coarsen.hpp"

#include <vector>

namespace bisect {

// A pass of coarsen() (coarsen.hpp) in which only the vertices with
// eligible[v] != 0 (and a parent edge) may go, instead of those whose star
// holds no newer vertex. `marks` (per cell) is updated as coarsen() keeps
// its marks: merged parents are marked, the cells compacted with the mesh.
// `removed` gets, per vertex of the mesh before the pass, whether it went.
// A mesh that is not marked or has no tree is left as it is.
CoarsenPass coarsen_pass_among(Mesh &mesh, std::vector<char> &marks,
                               const std::vector<char> &eligible, const CoarsenOptions &options,
                               std::vector<char> &removed);

} // namespace bisect
