// The bisection state as arrays made while writing (internal to the io
// layer). encode_state stores the state as cell and point arrays of doubles,
// 24 bytes per tet for the three cell arrays, alive through the whole write
// and the write's memory peak; the .vtu writer instead asks these sources
// for one value at a time.
#pragma once

#include "bisect/mesh.hpp"

#include <cstdint>
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
  // When set, value(first) .. value(first + n - 1) into out at once (the
  // writer's form: one call per piece of a block, not per value).
  std::function<void(std::size_t first, std::size_t n, double *out)> fill = {};
};

struct StateArrays {
  std::vector<ArraySource> cells, points; // what encode_state would add, in its order
  std::vector<std::uint8_t> flipped;      // per cell, 1: written with ids 0 and 1 swapped
  // Stored arrays the writer skips: the state's own names, and the tree's
  // (encode_state replaces them, or removes them when the mesh has no tree).
  bool hides(const std::string &name) const;
};

// Whether stream_state can stand for encode_state on `mesh`: a marked mesh
// whose marking is not Marking::Explicit (its edge ranks stay stored).
bool can_stream_state(const Mesh &mesh);
// The arrays encode_state would add, computed from the mesh on demand (the
// mesh must stay unchanged while they are used), and which cells the writer
// must write with their first two ids swapped to orient them positively, as
// encode_state does in place. The mesh itself is not changed, so other
// threads may read it meanwhile (the CLI's final check runs beside the
// write). The writer skips stored arrays of the same names, as encode_state
// replaces them. `orientation` (WriteOptions::orientation), when it has a
// sign per cell, says which cells to swap without computing their volumes.
StateArrays stream_state(const Mesh &mesh, const std::vector<std::int8_t> *orientation = nullptr);
// The tree's arrays (bisect:generation; bisect:parent_a, bisect:parent_b
// and, when sized for the mesh, bisect:level) as sources, appended to
// `cells` and `points`; encode_tree and stream_state share them.
void tree_sources(const Mesh &mesh, std::vector<ArraySource> &cells,
                  std::vector<ArraySource> &points);
// A source's values as a stored array of `rows` tuples.
DataArray materialize(const ArraySource &source, std::size_t rows);

// A bisect:* array where the reader left it: among the mesh's DataArrays or
// in a StoredState (looked in first). False when in neither.
class StateColumn {
public:
  static StateColumn find(const std::vector<DataArray> &data,
                          const std::vector<StoredArray> *stored, const char *name) {
    StateColumn c;
    if (stored)
      for (const StoredArray &a : *stored)
        if (a.name == name) {
          c.s_ = &a;
          return c;
        }
    for (const DataArray &a : data)
      if (a.name == name) {
        c.d_ = &a;
        return c;
      }
    return c;
  }
  explicit operator bool() const { return d_ || s_; }
  const std::string &name() const { return d_ ? d_->name : s_->name; }
  int components() const { return d_ ? d_->components : s_->components; }
  std::size_t size() const { return d_ ? d_->values.size() : s_->size(); }
  double operator[](std::size_t i) const { return d_ ? d_->values[i] : (*s_)[i]; }

private:
  const DataArray *d_ = nullptr;
  const StoredArray *s_ = nullptr;
};

// write_msh with the state's arrays streamed (null: none), flipped cells
// written with their first two ids swapped (msh.cpp).
void write_msh_with_state(const std::string &path, const Mesh &mesh, const StateArrays *state);

} // namespace bisect
