// Bisection and refine-to-conformity (ALGORITHMS.md §1, §6).
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <limits>
#include <vector>

namespace bisect {

// The precision limit, always on: an edge (p, q) is bisected only while its
// extent max_k |p_k - q_k| is at least kRelativeResolution times the largest
// coordinate magnitude max_k max(|p_k|, |q_k|) of its ends, and at least
// kAbsoluteResolution. Rounding the midpoint moves it by at most 2^-53 of
// that magnitude, so every new vertex stays within 2^-13 of the edge's extent
// of the true midpoint: children keep positive volumes and the shapes
// bisection guarantees, and no midpoint coincides with an end. The absolute
// floor keeps volumes and facet measures (up to the 6th power of a length in
// 4D) far from underflow.
inline constexpr double kRelativeResolution = 0x1p-40;  // about 9.1e-13
inline constexpr double kAbsoluteResolution = 0x1p-100; // about 7.9e-31

struct RefineLimits {
  std::size_t max_cells = std::numeric_limits<std::size_t>::max();
  // Largest vertex count: ids are 32-bit (kNoVertex is reserved); a caller may lower it.
  std::size_t max_vertices = std::numeric_limits<VertexId>::max() - 1;
  // Checked between passes; when set, the iteration is undone (Ctrl-C).
  const std::atomic<bool> *cancel = nullptr;
  // Not a limit: when given, receives for every cell the call appends (ids
  // from the input's cell count on, in order) the input cell it descends
  // from; an input cell's id is its first child's. Empty when the call was
  // undone. (The driver narrows the next selection with it.)
  std::vector<CellId> *origin = nullptr;
};

struct RefineResult {
  std::size_t selected = 0;       // cells bisected because they were selected
  std::size_t bisections = 0;     // all bisections, closure included
  std::size_t closure_passes = 0; // passes after the first
  bool limit_reached = false;     // the iteration was undone: it would pass a limit
  bool cancelled = false;         // the iteration was undone: limits.cancel was set
  bool precision_reached = false; // the iteration was undone: it would bisect an
                                  // edge below the precision limit (limit_reached
                                  // is set too)
  double kernel_seconds = 0;      // time in the bisection kernel proper (the rest
                                  // finds the cells to close)
};

// Bisects every cell of `selected` (ids of a marked mesh, no duplicates), then
// refines to conformity: cells with an edge whose midpoint exists are bisected
// by their own refinement edge until none is left. Children inherit cell data;
// point data is interpolated linearly at midpoints. When the result would pass
// a limit the mesh is left exactly as it was and `limit_reached` is set. The
// undo this needs is kept only where a limit can trip: a caller's max_cells or
// cancel, an edge near the precision limit, or 32-bit ids for a mesh within
// 16 times its size of them (a margin: an iteration about doubles the cells
// it touches; were a call to pass the ids without the undo, CheckError).
// Large passes bisect on all threads (threads.hpp), with the same result.
RefineResult refine(Mesh &mesh, const std::vector<CellId> &selected,
                    const RefineLimits &limits = {});

// As above, and first every cell holding an edge of `split` (pairs of vertex
// ids) is bisected by its own refinement edge until that edge is bisected
// (the edge's midpoint is made first, so that every cell around it ends up
// refined at it). An edge that no cell holds is skipped. Distributed
// refinement (distributed.hpp) uses it for the edges a neighbouring part
// bisected; the result is the smallest conforming refinement that bisects
// the selected cells and those edges.
RefineResult refine(Mesh &mesh, const std::vector<CellId> &selected,
                    const std::vector<std::array<VertexId, 2>> &split,
                    const RefineLimits &limits = {});

// Bisects every cell once, then refines to conformity.
RefineResult refine_uniform(Mesh &mesh);

} // namespace bisect
