// Regions that select the cells to bisect, read from a JSON spec.
//
// A region answers one question: does a closed simplex touch it? Answers are
// exact or conservative (never "no" for a simplex the region touches); each
// region type documents which in region.cpp.
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace bisect {

class Region {
public:
  virtual ~Region() = default;
  // `verts` holds dim+1 points of `dim` coordinates each (row after row).
  virtual bool touches(const double *verts, int dim) const = 0;
  // Every point the region contains lies in [lo, hi] (per coordinate);
  // unbounded coordinates give +-infinity. Used to skip far cells quickly.
  virtual void bounds(double *lo, double *hi, int dim) const = 0;
  // A second look at the cells touches() chose in one iteration (`selected`:
  // increasing ids into `mesh`); select_cells() calls it last. A region may
  // drop cells here, e.g. the levelset indicator keeps the fraction where the
  // function curves most. The default keeps them all.
  virtual void filter(const Mesh &, std::vector<CellId> &) const {}
  // Whether filter() ranks the selected cells against each other (so a part
  // of a mesh alone would select differently from the whole): the levelset
  // indicator. Such a filter keeps the round(rank_fraction() n) cells (at
  // least one) of the n selected with the largest rank_score(), ties going
  // to the cell whose vertices' coordinates, sorted, come first
  // (cell_coordinates_less), so that a distributed run, which ranks over all
  // its parts (select_cells of distributed.hpp), keeps the same cells.
  virtual bool filter_ranks_cells() const { return false; }
  virtual double rank_fraction() const { return 1; }
  virtual double rank_score(const Mesh &, CellId) const { return 0; }
  // Whether touches() may run in several threads at once (select_cells then
  // splits the cells among them; the selection is the same either way). The
  // default is no, for regions that keep state or call back into Python.
  virtual bool concurrent() const { return false; }
  // Whether a simplex that touches the region always lies in one that does
  // among the cells it was bisected from, and filter() keeps every cell: an
  // exact touches() of a region that stays put (sphere, hemisphere, box,
  // halfspace, moving sphere, and unions and intersections of them). Then
  // every cell an iteration could select descends from a cell the previous
  // one selected, and the driver tests only those (select_cells with
  // candidates; 3D ball, 12 iterations: 691,644 of the 1,845,340 cells
  // before the last).
  // The default is no (the levelset region samples, and its filter ranks).
  virtual bool monotone() const { return false; }
};

// Parses a region spec for a mesh of dimension `dim`. `origin` names where the
// text came from (a file path) for error messages. Throws InputError.
std::unique_ptr<Region> parse_region(const std::string &json_text, int dim,
                                     const std::string &origin);
// Reads and parses a spec file.
std::unique_ptr<Region> read_region(const std::string &path, int dim);

// The cells whose closed simplex touches the region, then region.filter().
std::vector<CellId> select_cells(const Mesh &mesh, const Region &region);
// The same among `candidates` only (a bit per cell, bit c % 64 of word
// c / 64; cells past its end are not candidates).
std::vector<CellId> select_cells(const Mesh &mesh, const Region &region,
                                 const std::vector<std::uint64_t> &candidates);
// The cells whose closed simplex touches the region, without the filter;
// among `candidates` when given.
std::vector<CellId> select_touching(const Mesh &mesh, const Region &region,
                                    const std::vector<std::uint64_t> *candidates = nullptr);
// The order of cells by their vertices' coordinates: each cell's vertices
// sorted lexicographically, then the two lists compared lexicographically
// (the same for every numbering of the cells and vertices).
bool cell_coordinates_less(const Mesh &mesh, CellId a, CellId b);
// A cell's vertices' coordinates, the vertices in lexicographic order (the
// first dim (dim + 1) entries): the key cell_coordinates_less compares.
std::array<double, 20> sorted_cell_coordinates(const Mesh &mesh, CellId c);

// select_cells as a selector for run_iterations (driver.hpp); `region` must
// outlive it.
std::function<std::vector<CellId>(const Mesh &)> region_selector(const Region &region);

} // namespace bisect
