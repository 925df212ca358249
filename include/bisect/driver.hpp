// The iteration driver: select, refine to conformity, measure, check, again.
// What `bisect refine` runs, for any selection (a region, an indicator, a
// caller's own rule), with limits, cancellation and a per-iteration callback.
#pragma once

#include "bisect/check.hpp"
#include "bisect/measure.hpp"
#include "bisect/mesh.hpp"
#include "bisect/refine.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bisect {

// The cells to bisect in the mesh as it is now (increasing ids, no repeats).
using Selector = std::function<std::vector<CellId>(const Mesh &)>;

struct DriverOptions {
  int iterations = 1;
  int depth = 1;             // bisections of each selected cell per iteration (refine_marked)
  std::size_t max_cells = 0; // stop before an iteration would pass it; 0: none
  double max_memory_gib = 0; // stop before an iteration estimated to need more
                             // than this in all; 0: more than is available now
  bool check_every_iteration = false;        // full conformity check against the input's
                                             // invariants after each iteration (slow)
  bool final_check = true;                   // the cheap final check (check_refined) at the end
  const std::atomic<bool> *cancel = nullptr; // set it to stop (the running
                                             // iteration is undone)
  // Whether `on_iteration` may change the mesh. When it does not, the last
  // iteration's quality pass also takes the final check's cell facts
  // (quality_with_cell_facts), and the check does not walk the cells again.
  bool on_iteration_changes_mesh = true;
  // When set, each selection after the first is select_among(mesh,
  // candidates) instead of select(mesh): `candidates` has a bit per cell
  // (bit c % 64 of word c / 64), set for the cells that descend from a cell
  // the previous iteration selected. For a selection that cannot pick any
  // other cell, such as a monotone region's (Region::monotone, select_cells
  // with candidates), the result is the same and only those cells are
  // looked at. Not used with depth > 1, nor when on_iteration may change the
  // mesh.
  std::function<std::vector<CellId>(const Mesh &, const std::vector<std::uint64_t> &)> select_among;
  // When true, the cell arrays (mesh.cell_data) leave the mesh while the
  // iterations run and come back, complete, when run_iterations returns or
  // throws: in between each cell carries only the id of the input cell it
  // descends from (4 bytes, where each array costs 8 per component). The
  // selector and on_iteration must not read mesh.cell_data then; refine()
  // and the checks do not. Not used with depth > 1. After an exception the
  // mesh is as refine() left it; cells it had not accounted for get cell
  // 0's values (and if memory runs out rebuilding them, the arrays are
  // dropped).
  bool cell_data_by_origin = false;
  // What the caller already has of the mesh as passed, so that
  // run_iterations does not walk it again: its invariants (all of them, as
  // prepare_input's InputFacts has them) and its quality summary.
  const Invariants *input_invariants = nullptr;
  const QualitySummary *input_quality = nullptr;
};

// One finished iteration.
struct IterationReport {
  int iteration = 0; // 1, 2, ...
  std::size_t cells = 0, vertices = 0;
  std::size_t first_new_vertex = 0; // vertices from here on were made by it
  std::size_t selected = 0, bisections = 0, closure_passes = 0;
  QualitySummary quality;
  double seconds = 0; // select + refine + quality
};

enum class StopReason {
  Done,            // every iteration ran
  NothingSelected, // the selection was empty (later ones would be too)
  CellLimit,       // max_cells or the 32-bit id limit (mesh before that iteration kept)
  MemoryLimit,     // the memory estimate (mesh before that iteration kept)
  PrecisionLimit,  // an edge finer than doubles resolve (mesh before that iteration kept)
  Cancelled,       // `cancel` was set (mesh before that iteration kept)
};

struct DriverResult {
  int iterations = 0; // iterations completed
  StopReason stop = StopReason::Done;
  std::string stop_message; // one line for the limits, else empty
  std::size_t bisections = 0;
  QualitySummary quality; // of the final mesh
  bool limit_reached() const {
    return stop == StopReason::CellLimit || stop == StopReason::MemoryLimit ||
           stop == StopReason::PrecisionLimit;
  }
  // Each final cell's orientation (+1, -1; CellFacts::signs) when the final
  // check took it from the last quality pass, else empty: for
  // WriteOptions::orientation.
  std::vector<std::int8_t> orientation;
  // Wall seconds by stage.
  double select_seconds = 0, refine_seconds = 0, quality_seconds = 0, check_seconds = 0;
};

// Runs up to options.iterations iterations of select + refine on a marked
// mesh. `on_iteration` (optional) sees each finished iteration and may read
// or change the mesh (the checks run after it). Throws CheckError when a check
// fails: the mesh is then not conforming and must not be written.
DriverResult
run_iterations(Mesh &mesh, const Selector &select, const DriverOptions &options = {},
               const std::function<void(const IterationReport &, Mesh &)> &on_iteration = {});

// Marks each cell of `marked` for `depth` bisections (its descendants inside
// it, `depth` generations down), then refines to conformity: the smallest
// conforming refinement that holds them. depth == dim halves the cells' size.
RefineResult refine_marked(Mesh &mesh, const std::vector<CellId> &marked, int depth = 1,
                           const RefineLimits &limits = {});

// Non-empty (why) when refining `selected` cells is estimated not to fit in
// memory: `max_gib` for the whole mesh, or (0) the memory available now.
std::string memory_shortfall(const Mesh &mesh, std::size_t selected, double max_gib);

} // namespace bisect
