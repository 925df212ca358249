// The file encoding of the bisection state (README, "Files").
#pragma once

#include "bisect/mesh.hpp"

#include <string>

namespace bisect {

// Names of the cell arrays that carry the state in files.
inline constexpr const char *kOrderArray = "bisect:order";     // dim+1 comps
inline constexpr const char *kStageArray = "bisect:stage";     // 0 Opposite, 1 Maubach
inline constexpr const char *kTagArray = "bisect:tag";         // see mesh.hpp
inline constexpr const char *kMarkingArray = "bisect:marking"; // 0 index, 1 longest, 2 sorted, 3 explicit
// Explicit marking only: per cell, the rank of each of its dim(dim+1)/2 edges
// (i, j), i < j, of the stored connectivity, in the order (0,1), (0,2), ...,
// (n-1,n); -1 for an edge without rank.
inline constexpr const char *kEdgeRankArray = "bisect:edge_rank";

// Before writing: orients every cell positively in `cells` and stores the
// tuple as the `bisect:*` cell arrays (tuple[i] = cell[order[i]]).
void encode_state(Mesh &mesh);
// After reading: when the `bisect:*` arrays are present and valid, restores
// the tuples, Stage and tag, removes the arrays and returns true. Returns
// false (and leaves the mesh unmarked) when they are absent. Throws
// InputError naming `path` and the first offending cell when they are
// present but invalid: a value out of range (marking, stage, tag, order not a
// permutation, edge ranks), or a state that is inconsistent (see
// check_state_consistency).
bool decode_state(Mesh &mesh, const std::string &path);
// After writing an encoded mesh: restores the tuples encode_state reordered
// and removes the bisect:* arrays, so the mesh is as before encode_state.
void strip_state(Mesh &mesh);

} // namespace bisect
