// Coarsening along the bisection tree (ALGORITHMS.md §10): the inverse of
// refine(): each pass undoes the newest refinement iteration around each vertex.
#pragma once

#include "bisect/mesh.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace bisect {

struct CoarsenOptions {
  int passes = 1; // 0: until a pass removes nothing
  // Cell arrays whose parent value is the sum of the children's (e.g. a
  // count or a mass); every other cell array takes the children's common
  // value when they agree, else their volume-weighted mean (the two children
  // of a bisection have equal volumes, so the plain mean).
  std::vector<std::string> sum_arrays;
  // Cell arrays whose parent value is the smaller of its children's, e.g.
  // bisect:origin, an index into an earlier mesh: the lowest index merged
  // into the parent, whatever order the cells are in (a distributed
  // coarsening gathers them in another order).
  std::vector<std::string> min_arrays;
};

struct CoarsenPass {
  int pass = 0;                        // 1, 2, ...
  std::size_t removed_vertices = 0;    // by this pass
  std::size_t merged_pairs = 0;        // by this pass (cells removed)
  std::size_t cells = 0, vertices = 0; // after it
  // Distributed coarsen (distributed.hpp) only: the rounds in which cells
  // moved between parts, and how many moved in all.
  int rounds = 0;
  std::size_t moved_cells = 0;
};

struct CoarsenResult {
  int passes = 0;                   // passes that removed something (it stops after
                                    // the first that removes nothing)
  std::size_t removed_vertices = 0; // in all
  std::size_t merged_pairs = 0;     // in all: the mesh has this many cells fewer
};

// Runs up to options.passes passes on a marked mesh with a tree (mesh.hpp;
// without one nothing changes). `marked_cells` has one entry per cell (non-
// zero: may be merged away). A made vertex z can go when its whole star is
// marked and consists of pairs of siblings: the two children of one
// bisection of z's parent edge, each pair checked by bisecting the
// reconstructed parent again (tuple, stage, tag) and getting exactly the pair.
// Each pair is replaced by that parent, with generation one less, in the
// slot of the child with the smaller id. A pass undoes the newest level
// (mesh.hpp) around each vertex: it removes, in sweeps until none removes
// anything, the vertices no vertex of whose star is of a newer level; so the
// newest level of the whole mesh goes in every pass, and refining N times
// and coarsening everything N passes gives the input back. Removed cells and
// vertices are compacted out at the end of a pass (survivors keep their
// relative order). A merged parent counts as marked. Generation-0 cells and
// original vertices are never removed. Cell arrays: see CoarsenOptions;
// point arrays keep their values at the surviving vertices. The result is
// conforming when the input is. `on_pass` (optional) sees each finished pass.
CoarsenResult coarsen(Mesh &mesh, const std::vector<char> &marked_cells,
                      const CoarsenOptions &options = {},
                      const std::function<void(const CoarsenPass &)> &on_pass = {});

} // namespace bisect
