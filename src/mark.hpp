// Marking: the global edge order and the initial bisection state of every cell
// (ALGORITHMS.md §2-4), and the cell arrays that carry that state in files.
#pragma once

#include "mesh.hpp"

#include <optional>
#include <string>
#include <vector>

namespace bisect {

// Strict total order on edges. `index`: key (min id, max id). `longest`:
// longer first (squared length computed from the endpoints in sorted-id order
// so every cell computes the identical double), ties by the index key.
// `sorted` uses the index order for the (unused) consistent edges.
struct EdgeOrder {
  Marking marking = Marking::Index;
  const std::vector<double> *coords = nullptr; // the mesh's, which may grow
  int dim = 0;

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

// Gives every cell its initial tuple, Stage and tag for `marking`:
//   sorted:        (x0 < ... < xn)_n, Maubach.
//   index/longest: 2D (alpha, gamma, beta)_2; 3D planar tets (a, c, b, d)_2
//                  and A/M/O tets Opposite; 4D every cell Opposite (Stage 1).
void mark_mesh(Mesh &mesh, Marking marking);

// The Arnold type of a 3D tet under the order (for tests and `bisect quality`).
enum class TetType { Planar, Adjacent, Mixed, Opposite };
TetType classify_tet(const EdgeOrder &order, const VertexId *ids);

// Names of the cell arrays that carry the state in files.
inline constexpr const char *kOrderArray = "bisect:order";     // dim+1 comps
inline constexpr const char *kStageArray = "bisect:stage";     // 0 Opposite, 1 Maubach
inline constexpr const char *kTagArray = "bisect:tag";         // see mesh.hpp
inline constexpr const char *kMarkingArray = "bisect:marking"; // 0 index, 1 longest, 2 sorted

// Before writing: orients every cell positively in `cells` and stores the
// tuple as the `bisect:*` cell arrays (tuple[i] = cell[order[i]]).
void encode_state(Mesh &mesh);
// After reading: when the `bisect:*` arrays are present and valid, restores
// the tuples, Stage and tag, removes the arrays and returns true. Returns
// false (and leaves the mesh unmarked) when they are absent. Throws
// InputError naming `path` when they are present but inconsistent.
bool decode_state(Mesh &mesh, const std::string &path);

std::optional<Marking> parse_marking(const std::string &name);
const char *marking_name(Marking marking);

} // namespace bisect
