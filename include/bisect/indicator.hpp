// Marking by a solver's error indicator (ALGORITHMS.md §9): which cells to
// refine (or coarsen) from one value per cell.
#pragma once

#include "bisect/mesh.hpp"

#include <string>
#include <vector>

namespace bisect {

enum class IndicatorRule {
  Above,  // the cells whose value is greater than the parameter
  Below,  // the cells whose value is less than the parameter (coarsening)
  Top,    // the ceil(F * cells) cells with the largest values, ties to the lower id (0 < F <= 1)
  Dorfler // the smallest set, largest values first (ties to the lower id), whose sum of
          // squares reaches theta times the total (0 < theta <= 1; values >= 0)
};

// The marked cells (increasing ids). Throws UsageError for a parameter out of
// range and InputError (naming `file`, and the cell as `mesh` numbers it when
// given: see names.hpp) for a negative value under Dorfler.
std::vector<CellId> mark_by_indicator(const std::vector<double> &values, IndicatorRule rule,
                                      double parameter, const std::string &file = {},
                                      const Mesh *mesh = nullptr);

// One value per cell from the array `name` of `mesh`: a one-component cell
// array, or a one-component point array (a cell's value is the largest of its
// vertices'). Throws InputError naming `file`: no such array (the message
// lists the arrays the mesh has), several components, a NaN or infinite value
// (naming the first cell or vertex).
std::vector<double> cell_indicator(const Mesh &mesh, const std::string &name,
                                   const std::string &file = {});

} // namespace bisect
