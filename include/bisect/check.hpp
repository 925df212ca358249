// Conformity checks (ALGORITHMS.md §7), shared by the tests and `bisect check`.
#pragma once

#include "bisect/measure.hpp"
#include "bisect/mesh.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bisect {

// Quantities refinement must leave unchanged.
struct Invariants {
  double volume = 0;           // sum of |cell volume|
  double boundary_measure = 0; // sum of measures of facets owned by one cell
  long long euler = 0;         // V - E + F - ... over the used vertices
  std::size_t boundary_facets = 0;
};
// Without `euler` the Euler characteristic (the costly part) is left 0.
Invariants measure_invariants(const Mesh &mesh, bool euler = true);

struct CheckResult {
  bool ok = true;
  std::string failure; // the first failure, one line; empty when ok
};

struct CheckOptions {
  // The caller vouches that the mesh was made by bisection (new vertices at
  // edge midpoints) from a valid mesh whose invariants are `original`. Then
  // a hanging node, or a face split differently by its two cells, leaves
  // unmatched facets inside the domain, each counted as boundary, so the
  // boundary measure grows by at least twice the smallest boundary facet:
  // while every boundary facet exceeds 1e-8 of the boundary measure (far
  // above its 1e-9 tolerance), the geometric search for vertices on boundary
  // facets is skipped. It runs anyway without `original` or with smaller
  // facets. For the fuzzer's small meshes; `bisect` itself never sets it.
  bool refined_from_original = false;
};

// Checks: every facet shared by at most two cells; no degenerate cell; across
// every interior facet the two opposite vertices lie on opposite sides (no
// inverted or folded cell); no hanging node (a vertex on a boundary facet it
// does not belong to); no face split differently by the cells on its two
// sides (the centroid of a boundary facet on another boundary facet); and,
// when `original` is given, volume, boundary
// measure (relative tolerance 1e-9) and Euler characteristic unchanged.
CheckResult check_conformity(const Mesh &mesh, const Invariants *original = nullptr,
                             const CheckOptions &options = {});

// The invariants' part of check_conformity: volume and boundary measure
// within a relative 1e-9 of `original`'s, the same Euler characteristic;
// the first that differs, in check_conformity's words.
CheckResult compare_invariants(const Invariants &original, const Invariants &now);

// Calls visit(a, i, b, j) once for every facet shared by exactly two cells:
// cells a and b, and the local index (in each cell's tuple) of the vertex
// opposite the facet. Facets come in increasing order of their sorted ids;
// the walk stops when visit returns false.
void for_each_interior_facet(const Mesh &mesh,
                             const std::function<bool(CellId, int, CellId, int)> &visit);

// The facets shared by two cells, each as its two cells (the smaller id
// first), in increasing order of the facet's sorted vertex ids, in pieces:
// what for_each_interior_facet visits, recorded by prepare_input.
using InteriorFacets = std::vector<std::vector<std::array<CellId, 2>>>;
// The same visit from a record of `mesh`'s interior facets (the local
// indices from the cells' tuples as they are now).
void for_each_interior_facet(const Mesh &mesh, const InteriorFacets &facets,
                             const std::function<bool(CellId, int, CellId, int)> &visit);
// The same for one piece of the record (a thread may visit each piece).
void for_each_interior_facet(const Mesh &mesh, const std::vector<std::array<CellId, 2>> &piece,
                             const std::function<bool(CellId, int, CellId, int)> &visit);

// The cheap final check `bisect refine` runs by default before writing (a
// fraction of check_conformity's cost): no degenerate cell; every facet in at
// most two cells; across every interior facet the two opposite vertices on
// opposite sides (no inverted or folded cell); volume and boundary measure
// equal to `original`'s (relative 1e-9). For a mesh made by bisection from a
// valid one, a hanging node or a face split differently from its two sides
// leaves unmatched facets counted as boundary, which grows the boundary
// measure by at least twice the smallest boundary facet; when that facet is
// below 1e-8 of the boundary measure, the geometric search of check_conformity
// for vertices and facet centroids on boundary facets runs as well.
//
// `facts`, when given and taken from this mesh as it is now (see
// quality_with_cell_facts), replace the check's own first pass over the
// cells.
struct CellFacts;
CheckResult check_refined(const Mesh &mesh, const Invariants &original,
                          const CellFacts *facts = nullptr);

// What check_refined's first pass over the cells finds: each cell's
// orientation, the volume, the first degenerate cell, whether every id is
// in range. quality_with_cell_facts takes them in the same walk as the
// quality summary (both gather each cell's points and need its
// determinant), so that a caller that measures the quality of the mesh it
// is about to check walks the cells once. They describe the mesh as it was
// then: check_refined uses them only for a mesh of the same arrays and
// sizes, and a caller that changes cells or points in place in between must
// not pass them.
struct CellFacts {
  std::vector<std::int8_t> signs; // +1, -1, 0 for a degenerate cell
  double volume = 0;              // sum of |cell volume|
  std::size_t first_degenerate = std::size_t(-1);
  double its_volume = 0; // the first degenerate cell's signed volume
  bool ids_ok = true;
  // The mesh they were taken from.
  const VertexId *cells = nullptr;
  const double *coords = nullptr;
  std::size_t num_cells = 0, num_vertices = 0;
  bool describe(const Mesh &mesh) const {
    return cells == mesh.cells.data() && coords == mesh.coords.data() &&
           num_cells == mesh.num_cells() && num_vertices == mesh.num_vertices();
  }
};

// quality_summary (measure.hpp), with `facts` taken on the way.
QualitySummary quality_with_cell_facts(const Mesh &mesh, CellFacts &facts);

// Progress of a long load or validation: called as each step starts, with
// the step ("reading", "matching facets", ...) and an estimate of the
// fraction of the whole load done (0 to 1, from the steps' typical costs).
using LoadProgress = std::function<void(const char *step, double done)>;

// Validates a freshly read mesh and orients every cell positively. Throws
// InputError naming `path`: NaN/Inf coordinates, ids out of range, repeated
// vertex in a cell, zero-volume cells, a facet shared by three or more cells,
// a hanging node (a vertex lying on a boundary facet it does not belong to,
// found with a grid over the boundary vertices), a face split differently on
// its two sides (a boundary facet's centroid on another boundary facet).
// `progress`, when set, hears of each step (done from 0.3 to 0.95: the read
// before it is about 0.3 of a load).
// What validation finds on its way that its callers would otherwise walk the
// mesh again for (the `facts` of prepare_input).
struct InputFacts {
  bool want_interior = false; // set by the caller: record `interior`
  bool want_quality = false;  // set by the caller: fill `quality`
  Invariants invariants;      // all of them (the same values as measure_invariants)
  InteriorFacets interior;
  // quality_summary of the input, from validation's own pass over the cells
  // (in the stored vertex order: the mean may differ from a later
  // quality_summary in its last bits).
  QualitySummary quality;
};
void prepare_input(Mesh &mesh, const std::string &path, const LoadProgress &progress = {},
                   InputFacts *facts = nullptr);

// The index of the first entity of `block` (mesh.hpp, Entities) that is not a
// face of some cell of `mesh` (ids out of range included), or
// std::size_t(-1) when every one is. Linear: the entities are hashed, then
// the cells' faces of the block's dimension looked up.
std::size_t first_entity_not_a_face(const Mesh &mesh, const Entities &block);

} // namespace bisect
