// The mesh is plain data: flat arrays and nothing clever (STYLE.md §1-2).
//
// Every cell is an ordered tuple of dim+1 global vertex ids plus a small
// bisection state (ALGORITHMS.md §1). Algorithms are free functions in the
// other files of src/, one stage per file.
#pragma once

#include "bisect/error.hpp"

#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace bisect {

using VertexId = std::uint32_t;
using CellId = std::uint32_t;
inline constexpr VertexId kNoVertex = std::numeric_limits<VertexId>::max();
inline constexpr CellId kNoCell = std::numeric_limits<CellId>::max();

// Where an element is in its bisection sequence (see numbering.hpp).
//  - Opposite: Stage 1, the "opposite-the-new-vertex" rule. `tag` counts the
//    new vertices stored at the front of the tuple (0 for an initial element);
//    the rest of the tuple is the old sub-simplex whose consistent edge (in the
//    mesh's global edge order) is the refinement edge.
//  - Maubach: the tuple (x0..xn) with tag d in 1..n; refinement edge (x0, xd).
enum class Stage : std::uint8_t { Opposite = 0, Maubach = 1 };

// The global edge order all marks come from (ALGORITHMS.md §2, §4).
// Explicit: the order is the mesh's `edge_rank` table (forced marks, e.g. for
// one pentatope of a chosen type); unranked edges come after every ranked
// one, among themselves by index.
enum class Marking : std::uint8_t { Index, Longest, Sorted, Explicit };

// Key of the edge {a, b} in `Mesh::edge_rank`.
inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  if (a > b)
    std::swap(a, b);
  return std::uint64_t(a) << 32 | b;
}

// The type an array has in files. Values are held as doubles (exact for
// every integer up to 2^53), and written back in this type. Integer point
// arrays are labels: refinement gives a new vertex the value both ends of its
// edge share, else label_sentinel(type). Unknown (arrays a format does not
// type, e.g. Gmsh's $ElementData, or made in memory): cell arrays whose
// values are all 32-bit integers are written as Int32, the rest as Float64.
enum class ValueType : std::uint8_t {
  Unknown,
  Float32,
  Float64,
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64
};
inline bool is_integer_type(ValueType t) {
  return t >= ValueType::Int8;
}
inline bool is_unsigned_type(ValueType t) {
  return t == ValueType::UInt8 || t == ValueType::UInt16 || t == ValueType::UInt32 ||
         t == ValueType::UInt64;
}
// -1 for signed integer types (and label arrays of unknown type), the largest
// value for unsigned ones.
inline double label_sentinel(ValueType t) {
  switch (t) {
  case ValueType::UInt8:
    return 255.0;
  case ValueType::UInt16:
    return 65535.0;
  case ValueType::UInt32:
    return 4294967295.0;
  case ValueType::UInt64:
    return 18446744073709551615.0;
  default:
    return -1.0;
  }
}

// A named array attached to points or cells; `components` values per entity.
struct DataArray {
  std::string name;
  int components = 1;
  std::vector<double> values;
  ValueType type = ValueType::Unknown;
};

// Point arrays that label vertices rather than sample a field: `colour` (the
// vertex colouring of bisect colour / extrude) and `slice` (the time slice of
// an extruded vertex). Averaging labels is meaningless, so a vertex made by
// bisection or by slicing between two vertices gets kNoLabel instead.
inline constexpr double kNoLabel = -1;
inline bool is_label_array(const std::string &name) {
  return name == "colour" || name == "slice";
}

// Tagged lower-dimensional cells that travel with the mesh: boundary facets,
// embedded (internal) surfaces, curves and points of Gmsh physical groups,
// or the lower-dimensional cells of a .vtu grid. Each is a face of some
// cell of the mesh (the readers check it). One block per dimension below the
// mesh's, in increasing dimension; a mesh read without any has none.
//  - vertices: dim+1 ids per entity, as in the file (order carries no
//    meaning: bisection and the face lookups use the sorted ids);
//  - data: one tuple per entity, e.g. gmsh:physical and gmsh:geometrical
//    (Gmsh's physical and elementary tags) and the values of a .vtu's cell
//    arrays for that cell.
// refine() splits an entity with the cells it bounds (both halves keep its
// data), coarsen() merges the halves back; code that renumbers vertices
// (coarsening, the readers) keeps the ids right. Tools that build a new mesh
// (extrude, slice, generate, colour's barycentric subdivision) drop them.
struct Entities {
  int dim = 0; // 0 points, 1 edges, 2 triangles, 3 tetrahedra (in 4D)
  std::vector<VertexId> vertices;
  std::vector<DataArray> data;
  std::size_t size() const { return vertices.size() / std::size_t(dim + 1); }
  const VertexId *entity(std::size_t i) const { return vertices.data() + i * std::size_t(dim + 1); }
};

// A name given to a physical tag of a dimension (Gmsh's $PhysicalNames,
// meshio's field_data in a .vtu).
struct PhysicalName {
  int dim = 0;
  int tag = 0;
  std::string name;
};

// How messages about a mesh as read name its vertices and cells: 0-based
// indices ("vertex 12", "cell 5") unless a reader says otherwise. The .msh
// reader records Gmsh's node and element tags, so that messages name them
// ("node 205", "element 17"); names.hpp formats every message through it.
// It applies only while sized for the mesh (`vertices`, `cells`); refine()
// and coarsen() clear it, and so must other code that renumbers.
struct FileNumbering {
  bool gmsh = false;                       // names are Gmsh node and element tags
  std::size_t vertices = 0, cells = 0;     // the counts it was made for
  std::vector<std::uint64_t> node_tags;    // per vertex; empty: node_base + index
  std::uint64_t node_base = 1;             //
  std::vector<std::uint64_t> element_tags; // per cell; empty: element_base + index
  std::uint64_t element_base = 1;
  std::uint64_t node(VertexId v) const { return node_tags.empty() ? node_base + v : node_tags[v]; }
  std::uint64_t element(std::uint32_t c) const {
    return element_tags.empty() ? element_base + c : element_tags[c];
  }
};

struct Mesh {
  int dim = 0;                   // 2, 3 or 4: space dimension == cell dimension
  std::vector<double> coords;    // dim values per vertex
  std::vector<VertexId> cells;   // dim+1 ids per cell, in tuple order
  std::vector<Stage> stage;      // per cell; empty until the mesh is marked
  std::vector<std::uint8_t> tag; // per cell; meaning depends on stage
  Marking marking = Marking::Index;
  std::unordered_map<std::uint64_t, std::uint32_t> edge_rank; // Marking::Explicit only
  std::vector<DataArray> point_data;
  std::vector<DataArray> cell_data;
  std::vector<Entities> entities; // see Entities; usually empty
  std::vector<PhysicalName> physical_names;
  FileNumbering numbering; // see FileNumbering; default: 0-based indices
  // The bisection tree, what coarsening needs (ALGORITHMS.md §10). Either
  // both empty (no tree: every cell has generation 0 and every vertex is
  // original) or sized for the mesh: refine() fills them in (O(1) per
  // bisection), coarsen() reads them, the writers carry them as the arrays
  // bisect:generation, bisect:parent_a, bisect:parent_b (state.hpp).
  //  - generation, per cell: bisections since the sequence started (cells of
  //    the mesh where it started, or read without the array, have 0). 2 bytes.
  //  - parent_edge, 2 per vertex: the ends of the edge the vertex was made
  //    the midpoint of, both smaller ids than the vertex; kNoVertex twice for
  //    an original vertex. 8 bytes per vertex (about 1.5 per cell in 3D).
  //  - level, per vertex: the refine() call that made it, counted over the
  //    sequence (0 for an original vertex, 1 for the first call's, ...); a
  //    coarsening pass undoes the newest level around each vertex, so N
  //    passes of coarsen undo N refinement iterations. Optional: when not
  //    sized for the mesh (a file without the array), every made vertex
  //    counts as level 1. 2 bytes per vertex.
  // Code that adds, removes or renumbers cells or vertices of a mesh without
  // keeping these up to date must clear them (clear_tree); refine() treats
  // arrays not sized for the mesh as no tree.
  std::vector<std::uint16_t> generation;
  std::vector<VertexId> parent_edge;
  std::vector<std::uint16_t> level;

  std::size_t num_vertices() const { return dim ? coords.size() / dim : 0; }
  std::size_t num_cells() const { return dim ? cells.size() / (dim + 1) : 0; }
  int cell_size() const { return dim + 1; }
  bool marked() const { return !stage.empty(); }
  // True when the tree arrays are sized for the mesh (see above).
  bool has_tree() const {
    return generation.size() == num_cells() && parent_edge.size() == 2 * num_vertices() &&
           num_cells() > 0;
  }
  void clear_tree() {
    generation.clear();
    parent_edge.clear();
    level.clear();
  }
  const double *point(VertexId v) const { return coords.data() + std::size_t(v) * dim; }
  const VertexId *cell(CellId c) const { return cells.data() + std::size_t(c) * (dim + 1); }
  VertexId *cell(CellId c) { return cells.data() + std::size_t(c) * (dim + 1); }
};

// A triangle mesh read from a plane z = c (c != 0, or with rounding noise in
// z) keeps each vertex's z in this point array: refinement interpolates it
// like any point array (exactly, for a plane), and the writers put it back
// into the third coordinate instead of writing it as an array.
inline constexpr const char *kPlaneZArray = "bisect:z";

} // namespace bisect
