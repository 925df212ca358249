// The bisection state as arrays made while writing (internal to the io
// layer). encode_state stores the state as cell and point arrays of doubles,
// 24 bytes per tet for the three cell arrays, alive through the whole write
// and the write's memory peak; the .vtu writer instead asks these sources
// for one value at a time.
#pragma once

#include "bisect/mesh.hpp"

#include <functional>
#include <string>
#include <vector>

namespace bisect {

// An array written from a function: value(i) for i < rows * components,
// called from several threads at once.
struct ArraySource {
  std::string name;
  int components = 1;
  ValueType type = ValueType::Int32;
  std::function<double(std::size_t)> value;
};

struct StateArrays {
  std::vector<ArraySource> cells, points; // what encode_state would add, in its order
  std::vector<bool> flipped;              // per cell: tuple positions 0 and 1 swapped
  // Stored arrays the writer skips: the state's own names, and the tree's
  // (encode_state replaces them, or removes them when the mesh has no tree).
  bool hides(const std::string &name) const;
};

// Whether stream_state can stand for encode_state on `mesh`: a marked mesh
// whose marking is not Marking::Explicit (its edge ranks stay stored).
bool can_stream_state(const Mesh &mesh);
// Orients every cell positively in `cells`, as encode_state does, and
// returns the arrays encode_state would add, computed from the mesh on
// demand (the mesh must stay unchanged while they are used). The writer
// skips stored arrays of the same names, as encode_state replaces them.
StateArrays stream_state(Mesh &mesh);
// The tree's arrays (bisect:generation; bisect:parent_a, bisect:parent_b
// and, when sized for the mesh, bisect:level) as sources, appended to
// `cells` and `points`; encode_tree and stream_state share them.
void tree_sources(const Mesh &mesh, std::vector<ArraySource> &cells,
                  std::vector<ArraySource> &points);
// A source's values as a stored array of `rows` tuples.
DataArray materialize(const ArraySource &source, std::size_t rows);
// Puts the tuples back as they were before stream_state.
void unstream_state(Mesh &mesh, const StateArrays &state);

} // namespace bisect
