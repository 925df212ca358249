// Marking: the global edge order and the initial bisection state of every cell
// (ALGORITHMS.md §2-4), and the cell arrays that carry that state in files.
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace bisect {

// Strict total order on edges. `index`: key (min id, max id). `longest`:
// longer first (squared length computed from the endpoints in sorted-id order
// so every cell computes the identical double), ties by the index key.
// `sorted` uses the index order for the (unused) consistent edges.
// `explicit`: ranked edges first, by rank; the rest by the index key.
struct EdgeOrder {
  Marking marking = Marking::Index;
  const std::vector<double> *coords = nullptr; // the mesh's, which may grow
  int dim = 0;
  const std::unordered_map<std::uint64_t, std::uint32_t> *rank = nullptr; // explicit only

  // True when edge {a, b} comes before edge {c, d}.
  bool before(VertexId a, VertexId b, VertexId c, VertexId d) const;
};
EdgeOrder edge_order(const Mesh &mesh);

// Local indices (i, j) in ids[0..count) of the consistent edge: the smallest
// edge of the sub-simplex in the order.
struct EdgePick {
  int first, second;
};
EdgePick consistent_edge(const EdgeOrder &order, const VertexId *ids, int count);

// Writes the Maubach tuple (alpha, gamma, beta) of triangle t: (alpha, beta)
// is its consistent edge, gamma the third vertex (ALGORITHMS.md §4).
void triangle_tuple(const EdgeOrder &order, const VertexId *t, VertexId *out);

// One Stage 1 ("opposite the new vertex") bisection of the cell x (n+1 ids:
// its t new vertices first, then its old sub-simplex; numbering.hpp).
// opposite_edge: the local indices of its refinement edge, the consistent
// edge of the old sub-simplex. opposite_children: with z the midpoint of that
// edge, writes the two children (the first drops the edge's first end) and
// the Stage and tag both children get.
EdgePick opposite_edge(const EdgeOrder &order, const VertexId *x, int n, int t);
void opposite_children(const EdgeOrder &order, const VertexId *x, int n, int t, EdgePick edge,
                       VertexId z, VertexId *c1, VertexId *c2, Stage &child_stage, int &child_tag);

// Gives every cell its initial tuple, Stage and tag for `marking`:
//   sorted:        (x0 < ... < xn)_n, Maubach.
//   index/longest: 2D (alpha, gamma, beta)_2; 3D planar tets (a, c, b, d)_2
//                  and A/M/O tets Opposite; 4D every cell Opposite (Stage 1).
void mark_mesh(Mesh &mesh, Marking marking);
// Marks an unmarked mesh with `marking` and returns true; leaves a marked one
// (e.g. with the state load_mesh restored) as it is and returns false.
bool ensure_marked(Mesh &mesh, Marking marking = Marking::Index);

// The Arnold type of a 3D tet under the order (for tests and `bisect quality`).
enum class TetType { Planar, Adjacent, Mixed, Opposite };
TetType classify_tet(const EdgeOrder &order, const VertexId *ids);

// The type of a 3D tet ("P", "A", "O", "M") or of a pentatope ("A_PO": how the
// level-1 marks relate to the level-0 mark, then each level-2 pair to its
// level-1 mark; seed 000 §3.2), under the order. The two lower letters are
// listed in the order P, A, O, M, since swapping the ends of the refinement
// edge swaps them.
std::string simplex_type(const EdgeOrder &order, const VertexId *ids, int dim);

// Forces the marks of a mesh's cells to a chosen type: finds a ranking of the
// edges of cell 0 (the only cell of a generated simplex) whose marks have
// `type`, stores it as the explicit edge order and marks the mesh. Throws
// UsageError naming the types that exist when `type` cannot arise
// from any global edge order (or the mesh is not a single 3D/4D simplex).
void force_type(Mesh &mesh, const std::string &type);

// Whether the cells' states can be refined conformingly: for every facet
// shared by two cells, the bisections the two cells would make on that facet
// (the split edges of its pieces, level after level, state_check_levels(dim)
// levels deep: a tet facet (4D) 4 levels, a Stage 1 step and its Maubach
// cycle of 3; a triangle facet (3D) 3 levels, while its newest-vertex
// bisection is fixed by the first) are the same from both sides. Necessary for conformity, and true
// of every state bisect writes. Empty when consistent, else one line naming the two cells and the
// facet. 2D needs no check (a facet is an edge, split at its midpoint from either side). Linear in
// the number of cells.
constexpr int state_check_levels(int dim) {
  return dim == 4 ? 4 : 3;
}
// `interior`, when given, is the mesh's record of its interior facets (see
// InteriorFacets in check.hpp), which saves a walk over its facets.
std::string
check_state_consistency(const Mesh &mesh,
                        const std::vector<std::vector<std::array<CellId, 2>>> *interior = nullptr);

std::optional<Marking> parse_marking(const std::string &name);
const char *marking_name(Marking marking);

} // namespace bisect
