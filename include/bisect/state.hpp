// The file encoding of the bisection state (README, "Files").
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace bisect {

// Names of the cell arrays that carry the state in files: one-component
// integers, so that every converter carries them (meshio to XDMF, Gmsh 2.2).
//  bisect:state = 16 * r + 8 * stage + tag, where r is the rank, among the
//    (dim+1)! permutations in lexicographic order, of the permutation p with
//    tuple[i] = cell[p[i]] (0: the stored vertex order is the tuple; bisect
//    writes 0 or, for a cell it swapped to orient it positively, the rank of
//    (1, 0, 2, ...)); stage 0 Stage 1 (Opposite), 1 Maubach; tag as in mesh.hpp.
//  bisect:marking = the global edge order (0 index, 1 longest, 2 sorted, 3 explicit).
inline constexpr const char *kStateArray = "bisect:state";
// refine --origin: per output cell, the index of the input cell it descends
// from (an ordinary Int32 cell array, inherited by children).
inline constexpr const char *kOriginArray = "bisect:origin";
inline constexpr int pack_state(int permutation_rank, Stage stage, int tag) {
  return permutation_rank * 16 + int(stage) * 8 + tag;
}
// The lexicographic rank of the permutation p of 0..k-1 (k <= 5), and back
// (false when rank is not below k!).
int permutation_rank(const int *p, int k);
bool permutation_of_rank(int rank, int k, int *p);

// Older files (still read): the tuple's permutation, stage and tag apart.
inline constexpr const char *kOrderArray = "bisect:order"; // dim+1 comps
inline constexpr const char *kStageArray = "bisect:stage"; // 0 Opposite, 1 Maubach
inline constexpr const char *kTagArray = "bisect:tag";     // see mesh.hpp
inline constexpr const char *kMarkingArray =
    "bisect:marking"; // 0 index, 1 longest, 2 sorted, 3 explicit
// Explicit marking only: per cell, the rank of each of its dim(dim+1)/2 edges
// (i, j), i < j, of the stored connectivity, in the order (0,1), (0,2), ...,
// (n-1,n); -1 for an edge without rank.
inline constexpr const char *kEdgeRankArray = "bisect:edge_rank";

// In the pieces of a distributed refine's .pvtu (distributed.hpp), per point:
// its id in the mesh the run started from (its input, or the last rebalance's
// whole mesh), -1 for a vertex made since. Ids >= 0 give the input vertices'
// order, which the global edge order of the marking depends on; read_pvtu
// merges pieces by them and drops the array.
inline constexpr const char *kGlobalIdArray = "bisect:global_id";

// The bisection tree (mesh.hpp, ALGORITHMS.md §10), one-component integer
// arrays so that converters that only take scalar fields (meshio's XDMF and
// Gmsh 2.2 writers) keep them:
//   bisect:generation (cell) generation of the cell, 0..kMaxGeneration
//   bisect:parent_a, bisect:parent_b (point) the ends of the edge the vertex
//     is the midpoint of, as ids of the file's points, both smaller than the
//     vertex's own id; -1 for an original vertex.
//   bisect:level (point) the refinement iteration that made the vertex, 0
//     for an original vertex (optional: without it every made vertex is
//     level 1, and one coarsening pass undoes as much as it can).
//   bisect:parent_rank (point, explicit marking only) the rank of the
//     vertex's parent edge in the explicit edge order, -1 for an original
//     vertex or an edge without rank. No cell holds a split edge, so
//     bisect:edge_rank cannot carry its rank, and coarsening needs it: the
//     Stage 1 parents it rebuilds are bisected by the order again.
// The deepest generation a file may give (see tree.cpp).
inline constexpr int kMaxGeneration = 8192;
inline constexpr const char *kGenerationArray = "bisect:generation";
inline constexpr const char *kParentAArray = "bisect:parent_a";
inline constexpr const char *kParentBArray = "bisect:parent_b";
inline constexpr const char *kLevelArray = "bisect:level";
inline constexpr const char *kParentRankArray = "bisect:parent_rank";

// The tree in the pieces of a .pvtu (a piece may lack a vertex's parents,
// so they are named by coordinates; read_pvtu turns these into the arrays
// above and drops them):
//   bisect:piece_generation (cell) as bisect:generation;
//   bisect:piece_level (point) as bisect:level;
//   bisect:piece_parents (point, 2 dim components) the coordinates of the
//     two ends of the vertex's parent edge; the vertex's own twice for an
//     original vertex.
inline constexpr const char *kPieceGenerationArray = "bisect:piece_generation";
inline constexpr const char *kPieceLevelArray = "bisect:piece_level";
inline constexpr const char *kPieceParentsArray = "bisect:piece_parents";

// Adds the tree arrays when the mesh has a tree; otherwise removes any
// (e.g. copied from another mesh's point data by a tool).
void encode_tree(Mesh &mesh);
// Moves the tree arrays, when present, into mesh.generation and
// mesh.parent_edge and removes them from the data; without them the mesh has
// no tree (every cell generation 0, every vertex original). Throws InputError
// naming `path` and the array: wrong component count, a value that is not an
// integer in range, parent ids not both -1 or both smaller than the vertex
// and distinct, or a vertex that is not the midpoint of its parent edge
// (relative 1e-6 of the edge's extent). With explicit marking (mesh.marking
// already decoded), the ranks bisect:parent_rank gives are added to
// mesh.edge_rank (InputError: not an integer -1..2^32-2, a rank for an
// original vertex, or an edge given two different ranks). Returns whether
// the arrays were there.
// `stored`: where the arrays are when not in the mesh's data (emptied).
struct StoredState; // below
bool decode_tree(Mesh &mesh, const std::string &path, StoredState *stored = nullptr);
// Removes the tree arrays from the data (the mesh's tree fields stay).
void strip_tree(Mesh &mesh);

// The state's arrays as a .vtu stores them, beside the mesh instead of in
// its DataArrays: bisect:state, bisect:marking, bisect:generation (cells),
// bisect:parent_a, bisect:parent_b, bisect:level (points), each in its
// file type (Int8, UInt8, Int16, UInt16 or Int32: 1 to 4 bytes a value,
// where a DataArray holds 8). read_mesh(path, stored) fills it from a
// one-piece .vtu and prepare_read_mesh / decode_state use it (a 31 M-tet
// refined file refined again: peak 108.9 -> 81.5 bytes per cell, with the
// reader's offsets no longer copied). Arrays of other types, .msh files and
// .vtu files of several pieces keep them as DataArrays; decode_state takes
// each array from either place.
struct StoredArray {
  std::string name;
  int components = 1;
  ValueType type = ValueType::Int32; // the file's
  std::variant<std::vector<std::int8_t>, std::vector<std::uint8_t>, std::vector<std::int16_t>,
               std::vector<std::uint16_t>, std::vector<std::int32_t>>
      values; // tuples * components, as for DataArray
  std::size_t size() const {
    return std::visit([](const auto &v) { return v.size(); }, values);
  }
  double operator[](std::size_t i) const {
    return std::visit([i](const auto &v) { return double(v[i]); }, values);
  }
};
struct StoredState {
  std::vector<StoredArray> cells, points;
  bool empty() const { return cells.empty() && points.empty(); }
};

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
// `interior`: as for check_state_consistency. `stored`: where the arrays
// are when not in the mesh's data (StoredState; emptied).
bool decode_state(Mesh &mesh, const std::string &path,
                  const std::vector<std::vector<std::array<CellId, 2>>> *interior = nullptr,
                  StoredState *stored = nullptr);
// After writing an encoded mesh: restores the tuples encode_state reordered
// and removes the bisect:* arrays, so the mesh is as before encode_state.
void strip_state(Mesh &mesh);

} // namespace bisect
