// VTK XML unstructured grid (.vtu) reading and writing, both bisect's own:
// vtu_read.cpp decodes a file (no VTK code runs on input, so no corrupt file
// can crash a VTK reader), vtu_write.cpp writes one. This file turns the
// decoded grid into a Mesh and checks a Mesh before writing.
//
// Conventions:
//  - 2D: triangles with all z == 0; 3D: tetrahedra.
//  - 4D: field data "SpatialDimension" == 4; Points hold (x, y, z); point
//    array "t" (Float64, 1 component) holds the 4th coordinate; every
//    pentatope is one VTK_POLY_VERTEX cell with 5 ids (VTK_CONVEX_POINT_SET
//    with 5 ids is accepted on reading).
//  - Tagged entities (mesh.hpp): lower-dimensional simplex cells (vertex,
//    line, triangle, tetra below the cell dimension) after the volume cells,
//    with their rows of the cell arrays; physical names as integer field
//    data (tag, dimension), meshio's convention.
#include "bisect/check.hpp"
#include "bisect/io.hpp"
#include "bisect/output.hpp"
#include "io/vtu_read.hpp"
#include "io/vtu_write.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace bisect {
namespace {

// ---------------------------------------------------------------------------
// Reading: vtu_read.cpp decodes the file; here the cells that make the mesh
// are chosen and renumbered.

// A linear VTK cell type: its topological dimension and number of point
// ids (exact, or at least `ids` when `variable`).
struct CellKind {
  const char *name;
  int dim;
  int ids;
  bool variable;
};

constexpr int kPolyVertex = 2, kTriangle = 5, kTetra = 10, kConvexPointSet = 41;

const CellKind *linear_cell(int type) {
  static const CellKind kinds[] = {
      {"empty cell", -1, 0, false},     {"vertex", 0, 1, false},
      {"poly-vertex", 0, 1, true},      {"line", 1, 2, false},
      {"poly-line", 1, 2, true},        {"triangle", 2, 3, false},
      {"triangle strip", 2, 3, true},   {"polygon", 2, 3, true},
      {"pixel", 2, 4, false},           {"quad", 2, 4, false},
      {"tetrahedron", 3, 4, false},     {"voxel", 3, 8, false},
      {"hexahedron", 3, 8, false},      {"wedge", 3, 6, false},
      {"pyramid", 3, 5, false},         {"pentagonal prism", 3, 10, false},
      {"hexagonal prism", 3, 12, false}};
  static const CellKind convex_point_set = {"convex point set", 3, 1, true};
  static const CellKind polyhedron = {"polyhedron", 3, 4, true};
  if (type >= 0 && type <= 16)
    return &kinds[type];
  if (type == kConvexPointSet)
    return &convex_point_set;
  if (type == 42)
    return &polyhedron;
  return nullptr;
}

// Every cell is a linear VTK cell with the number of ids its type has: no
// cell of the file is dropped without a reason.
void check_cell_types(const std::string &path, const vtu::Grid &g) {
  for (std::size_t c = 0; c < g.num_cells; ++c) {
    const int type = g.types[c];
    const std::int64_t n = g.offsets[c] - g.begin(c);
    const CellKind *kind = linear_cell(type);
    if (kind && kind->dim >= 0 && (kind->variable ? n >= kind->ids : n == kind->ids))
      continue;
    const std::string cell = "cell " + std::to_string(c);
    if (!kind)
      throw InputError(path, cell + " has VTK type " + std::to_string(type) +
                                 ", which is not a known linear cell type");
    if (kind->dim < 0)
      throw InputError(path, cell + " has VTK type 0 (an empty cell)");
    if (kind->variable ? n < kind->ids : n != kind->ids)
      throw InputError(path, cell + " (VTK type " + std::to_string(type) + ", " + kind->name +
                                 ") has " + std::to_string(n) + " point ids, expected " +
                                 (kind->variable ? "at least " : "") + std::to_string(kind->ids));
  }
}

std::string array_name(const vtu::Array &a, std::size_t index) {
  return a.name.empty() ? "unnamed" + std::to_string(index) : a.name;
}

// The first array of that name, numeric or not (as vtkFieldData::GetArray).
const vtu::Array *find_array(const std::vector<vtu::Array> &arrays, const char *name) {
  for (const auto &a : arrays)
    if (a.name == name)
      return &a;
  return nullptr;
}

// The 4D convention is on when field data "SpatialDimension" says 4.
bool is_4d(const vtu::Grid &g) {
  const vtu::Array *sd = find_array(g.field_data, "SpatialDimension");
  return sd && sd->numeric && !sd->values.empty() && sd->values[0] == 4.0;
}

// The cells kept by the reader (file ids) and the dimension they define;
// the lower-dimensional simplices (VTK vertex, line, triangle, tetra below
// the cell dimension) that become tagged entities (mesh.hpp), per dimension.
struct KeptCells {
  int dim = 0;
  std::vector<CellId> ids;
  std::vector<CellId> entity_ids[4];
};

constexpr int kVertex = 1, kLine = 3;

// The dimension of a simplex cell type (vertex, line, triangle, tetra), -1
// for the others.
int simplex_dim(int type) {
  switch (type) {
  case kVertex:
    return 0;
  case kLine:
    return 1;
  case kTriangle:
    return 2;
  case kTetra:
    return 3;
  default:
    return -1;
  }
}

KeptCells select_cells_4d(const std::string &path, const vtu::Grid &g) {
  KeptCells kept;
  kept.dim = 4;
  for (std::size_t c = 0; c < g.num_cells; ++c) {
    const int type = g.types[c];
    const std::int64_t npts = g.offsets[c] - g.begin(c);
    if (type == kPolyVertex || type == kConvexPointSet) {
      if (npts != 5)
        throw InputError(path, "4D mesh: cell " + std::to_string(c) + " has " +
                                   std::to_string(npts) + " vertices, expected 5");
      kept.ids.push_back(CellId(c));
    } else if (const int d = simplex_dim(type); d >= 0) {
      kept.entity_ids[d].push_back(CellId(c)); // a tagged boundary piece
    } else {
      // Anything else cannot be part of a pentatope mesh.
      throw InputError(path, "4D mesh: cell " + std::to_string(c) + " has VTK type " +
                                 std::to_string(type) +
                                 ", expected a 5-vertex poly-vertex (type 2)");
    }
  }
  if (kept.ids.empty())
    throw InputError(path, "4D mesh: no pentatopes (5-vertex poly-vertex cells)");
  return kept;
}

// Keeps the simplices of the highest dimension and, as entities, the lower-
// dimensional simplices; other lower-dimensional cells are ignored, a
// non-simplex cell of that dimension or higher is an error.
KeptCells select_cells(const std::string &path, const vtu::Grid &g) {
  int dim = 0;
  for (std::size_t c = 0; c < g.num_cells; ++c) {
    if (g.types[c] == kTetra)
      dim = 3;
    else if (g.types[c] == kTriangle && dim < 2)
      dim = 2;
  }
  if (dim == 0) {
    for (std::size_t c = 0; c < g.num_cells; ++c)
      if (linear_cell(g.types[c])->dim >= 2)
        throw InputError(path, "no triangles or tetrahedra (found non-simplex cells, VTK "
                               "type " +
                                   std::to_string(g.types[c]) + ")");
    throw InputError(path, "no triangles or tetrahedra");
  }
  const int simplex = dim == 2 ? kTriangle : kTetra;
  KeptCells kept;
  kept.dim = dim;
  kept.ids.reserve(g.num_cells);
  for (std::size_t c = 0; c < g.num_cells; ++c) {
    const int type = g.types[c];
    if (type == simplex)
      kept.ids.push_back(CellId(c));
    else if (linear_cell(type)->dim >= dim)
      throw InputError(path, "mixed non-simplex cells (VTK type " + std::to_string(type) + ")");
    else if (const int d = simplex_dim(type); d >= 0)
      kept.entity_ids[d].push_back(CellId(c));
    // (other lower-dimensional cells, e.g. quads or poly-lines, are ignored)
  }
  return kept;
}

ValueType value_type_named(const std::string &t) {
  static const std::pair<const char *, ValueType> names[] = {
      {"Float32", ValueType::Float32}, {"Float64", ValueType::Float64},
      {"Int8", ValueType::Int8},       {"UInt8", ValueType::UInt8},
      {"Int16", ValueType::Int16},     {"UInt16", ValueType::UInt16},
      {"Int32", ValueType::Int32},     {"UInt32", ValueType::UInt32},
      {"Int64", ValueType::Int64},     {"UInt64", ValueType::UInt64}};
  for (const auto &[n, v] : names)
    if (t == n)
      return v;
  return ValueType::Unknown;
}

// Keeps the tuples (of k values) of `v` at `rows` (increasing), moved to the
// front in place (rows[i] >= i, so no tuple is overwritten before it is
// read): a copy would touch as much fresh memory again, and a page fault
// per page of it is a large part of reading.
template <class T, class Row>
void keep_rows(std::vector<T> &v, std::size_t k, const std::vector<Row> &rows) {
  T *to = v.data();
  if (rows.size() * k != v.size())
    for (Row r : rows)
      for (std::size_t j = 0; j < k; ++j)
        *to++ = v[std::size_t(r) * k + j];
  v.resize(rows.size() * k);
}

// The selected tuples (file ids in `rows`, increasing) of `a`. With
// `in_place` a's values become the result (keep_rows). Otherwise copied,
// `a` left as it is.
template <class Row>
DataArray take_rows(vtu::Array &a, const std::string &name, const std::vector<Row> &rows,
                    bool in_place) {
  DataArray out;
  out.name = name;
  out.components = a.components;
  out.type = value_type_named(a.type);
  const std::size_t k = std::size_t(a.components);
  if (in_place) {
    keep_rows(a.values, k, rows);
    out.values = std::move(a.values);
    return out;
  }
  out.values.resize(rows.size() * k);
  double *to = out.values.data();
  for (Row r : rows)
    for (std::size_t j = 0; j < k; ++j)
      *to++ = a.values[std::size_t(r) * k + j];
  return out;
}

// take_rows in place for an array read in its file type (vtu::Array::ints).
template <class Row>
StoredArray take_stored_rows(vtu::Array &a, const std::string &name, const std::vector<Row> &rows) {
  StoredArray out;
  out.name = name;
  out.components = a.components;
  out.type = value_type_named(a.type);
  std::visit([&](auto &v) { keep_rows(v, std::size_t(a.components), rows); }, a.ints);
  out.values = std::move(a.ints);
  return out;
}

// The 4th coordinate array of the 4D convention, checked.
const vtu::Array &time_array(const std::string &path, const vtu::Grid &g) {
  const vtu::Array *t = find_array(g.point_data, "t");
  if (!t || !t->numeric)
    throw InputError(path,
                     "4D mesh: point data array 't' (4th coordinate) is missing or not numeric");
  if (t->components != 1)
    throw InputError(path, "4D mesh: point data array 't' has " + std::to_string(t->components) +
                               " components, expected 1");
  return *t; // one value per point: the reader checked the count
}

// The lower-dimensional simplices as tagged entities, each with its rows of
// the numeric cell arrays, except the bisect:* arrays (the state of volume
// cells; 0 in an entity's rows) and float arrays that are NaN in every row
// of the block (what the writer pads an entity's missing array with). Each
// must be a face of some cell.
// entity_blocks takes their vertices (before the connectivity is compacted),
// add_entities the rest.
std::vector<Entities> entity_blocks(const vtu::Grid &g, const KeptCells &kept,
                                    const std::vector<VertexId> &new_id) {
  std::vector<Entities> blocks;
  for (int d = 0; d < kept.dim; ++d) {
    const std::vector<CellId> &ids = kept.entity_ids[d];
    Entities &block = blocks.emplace_back();
    block.dim = d;
    block.vertices.reserve(ids.size() * std::size_t(d + 1));
    for (CellId c : ids) {
      const std::uint32_t *pts = g.connectivity.data() + g.begin(c);
      for (int k = 0; k <= d; ++k)
        block.vertices.push_back(new_id[pts[k]]); // kNoVertex: not a face
    }
  }
  return blocks;
}

void add_entities(const std::string &path, vtu::Grid &g, const KeptCells &kept,
                  std::vector<Entities> &&blocks, Mesh &mesh) {
  static const char *const kNames[4] = {"vertex", "line", "triangle", "tetra"};
  for (int d = 0; d < kept.dim; ++d) {
    const std::vector<CellId> &ids = kept.entity_ids[d];
    if (ids.empty())
      continue;
    Entities &block = blocks[std::size_t(d)];
    const std::size_t bad = first_entity_not_a_face(mesh, block);
    if (bad != std::size_t(-1))
      throw InputError(path, "cell " + std::to_string(ids[bad]) + " (" + kNames[d] +
                                 ") is not a face of the mesh");
    for (std::size_t i = 0; i < g.cell_data.size(); ++i) {
      vtu::Array &a = g.cell_data[i];
      const std::string name = array_name(a, i);
      if (!a.numeric || name.rfind("bisect:", 0) == 0)
        continue;
      DataArray rows = take_rows(a, name, ids, false);
      if (std::all_of(rows.values.begin(), rows.values.end(),
                      [](double v) { return std::isnan(v); }))
        continue;
      block.data.push_back(std::move(rows));
    }
    mesh.entities.push_back(std::move(block));
  }
}

// Field data in meshio's convention for physical names (what meshio keeps
// from a Gmsh file's $PhysicalNames): an integer array named after the
// group holding (tag, dimension).
void add_physical_names(const vtu::Grid &g, Mesh &mesh) {
  for (const vtu::Array &a : g.field_data) {
    if (!a.numeric || a.values.size() != 2 || a.name.empty() || a.name == "SpatialDimension" ||
        !is_integer_type(value_type_named(a.type)))
      continue;
    const double tag = a.values[0], dim = a.values[1];
    if (dim >= 0 && dim <= mesh.dim && tag >= INT_MIN && tag <= INT_MAX)
      mesh.physical_names.push_back({int(dim), int(tag), a.name});
  }
}

// `stored`: receives the arrays read as vtu::Array::ints (read_grid's
// keep_state_types).
Mesh grid_to_mesh(const std::string &path, vtu::Grid g, StoredState *stored = nullptr) {
  check_cell_types(path, g);
  const bool four = is_4d(g);
  const std::size_t np = g.num_points;
  if (g.num_cells >= std::size_t(kNoCell))
    throw InputError(path, "too many cells");
  KeptCells kept = four ? select_cells_4d(path, g) : select_cells(path, g);
  const vtu::Array *t = four ? &time_array(path, g) : nullptr;

  // Cells, with their vertices numbered compactly in file order. (Ids are
  // in range and each kept cell has dim + 1 of them: the reader and
  // check_cell_types made sure.)
  const int nvc = kept.dim + 1;
  std::vector<VertexId> new_id(np, kNoVertex);
  for (CellId c : kept.ids) {
    const std::uint32_t *pts = g.connectivity.data() + g.begin(c);
    for (int i = 0; i < nvc; ++i) {
      for (int j = 0; j < i; ++j)
        if (pts[j] == pts[i])
          throw InputError(path, "cell " + std::to_string(c) + " repeats point " +
                                     std::to_string(pts[i]));
      new_id[pts[i]] = 0; // used
    }
  }
  std::vector<VertexId> used; // file ids of the kept points, in order
  used.reserve(np);
  for (std::size_t p = 0; p < np; ++p)
    if (new_id[p] != kNoVertex) {
      new_id[p] = VertexId(used.size());
      used.push_back(VertexId(p));
    }
  const bool all_points = used.size() == np, all_cells = kept.ids.size() == g.num_cells;
  std::vector<Entities> blocks = entity_blocks(g, kept, new_id);

  Mesh mesh;
  mesh.dim = kept.dim;
  if (all_points && all_cells) {
    // Every cell kept, every point used in file order: the ids stay as they are.
    mesh.cells = std::move(g.connectivity);
  } else {
    // In place, as in take_rows: kept cell i starts at or after i * nvc
    // (each cell before it has at least one point), and its ids are read
    // before any is written.
    VertexId *to = g.connectivity.data();
    for (CellId c : kept.ids) {
      const std::uint32_t *pts = g.connectivity.data() + g.begin(c);
      VertexId ids[5];
      for (int i = 0; i < nvc; ++i)
        ids[i] = new_id[pts[i]];
      to = std::copy(ids, ids + nvc, to);
    }
    g.connectivity.resize(kept.ids.size() * std::size_t(nvc));
    mesh.cells = std::move(g.connectivity);
  }

  // Coordinates: (x, y) in 2D, (x, y, z) in 3D, (x, y, z, t) in 4D.
  const bool move_points = mesh.dim == 3 && all_points;
  bool off_plane = false;
  if (!move_points)
    mesh.coords.reserve(used.size() * std::size_t(mesh.dim));
  for (VertexId p : used) {
    double x[4] = {g.points[3 * p], g.points[3 * p + 1], g.points[3 * p + 2], 0};
    if (four)
      x[3] = t->values[p];
    for (int k = 0; k < (four ? 4 : 3); ++k)
      if (!std::isfinite(x[k]))
        throw InputError(path, "point " + std::to_string(p) + " has a non-finite coordinate");
    if (mesh.dim == 2 && x[2] != 0.0)
      off_plane = true;
    if (!move_points)
      mesh.coords.insert(mesh.coords.end(), x, x + mesh.dim);
  }
  if (move_points)
    mesh.coords = std::move(g.points); // x, y, z of every point, in order
  if (off_plane) {                     // see settle_plane in io.cpp
    DataArray z{kPlaneZArray, 1, {}};
    z.values.reserve(used.size());
    for (VertexId p : used)
      z.values.push_back(g.points[3 * p + 2]);
    mesh.point_data.push_back(std::move(z));
  }

  // Numeric point and cell arrays; "t" of the 4D convention is a coordinate.
  for (std::size_t i = 0; i < g.point_data.size(); ++i) {
    vtu::Array &a = g.point_data[i];
    if ((four && &a == t) || !a.numeric)
      continue;
    if (a.stored)
      stored->points.push_back(take_stored_rows(a, array_name(a, i), used));
    else
      mesh.point_data.push_back(take_rows(a, array_name(a, i), used, true));
  }
  add_entities(path, g, kept, std::move(blocks), mesh); // before the cell arrays are moved
  for (std::size_t i = 0; i < g.cell_data.size(); ++i) {
    vtu::Array &a = g.cell_data[i];
    if (a.stored)
      stored->cells.push_back(take_stored_rows(a, array_name(a, i), kept.ids));
    else if (a.numeric)
      mesh.cell_data.push_back(take_rows(a, array_name(a, i), kept.ids, true));
  }
  add_physical_names(g, mesh);
  return mesh;
}

// ---------------------------------------------------------------------------
// Writing.

void check_mesh_for_writing(const std::string &path, const Mesh &mesh) {
  auto fail = [&](const std::string &what) { throw CheckError(path + ": cannot write: " + what); };
  if (mesh.dim < 2 || mesh.dim > 4)
    fail("mesh dimension " + std::to_string(mesh.dim) + " is not 2, 3 or 4");
  if (mesh.coords.size() % mesh.dim || mesh.cells.size() % (mesh.dim + 1))
    fail("coordinate or cell array has a partial entry");
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  for (VertexId v : mesh.cells)
    if (v >= nv)
      fail("a cell refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
  for (const auto &a : mesh.point_data)
    if (a.components < 1 || a.values.size() != nv * a.components)
      fail("point array '" + a.name + "' does not have one tuple per vertex");
  for (const auto &a : mesh.cell_data)
    if (a.components < 1 || a.values.size() != nc * a.components)
      fail("cell array '" + a.name + "' does not have one tuple per cell");
  for (const Entities &b : mesh.entities) {
    if (b.dim < 0 || b.dim >= mesh.dim || b.vertices.size() % std::size_t(b.dim + 1))
      fail("a block of tagged entities of dimension " + std::to_string(b.dim) + " is malformed");
    for (VertexId v : b.vertices)
      if (v >= nv)
        fail("a tagged entity refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
    for (const auto &a : b.data)
      if (a.components < 1 || a.values.size() != b.size() * a.components)
        fail("entity array '" + a.name + "' does not have one tuple per entity");
  }
  if (mesh.dim == 4)
    for (const auto &a : mesh.point_data)
      if (a.name == "t")
        fail("point array 't' is reserved for the 4th coordinate of 4D meshes");
}

} // namespace

Mesh read_vtu(const std::string &path) {
  return grid_to_mesh(path, vtu::read_grid(path));
}

Mesh read_vtu(const std::string &path, StoredState &stored) {
  stored = {};
  return grid_to_mesh(path, vtu::read_grid(path, true), &stored);
}

void write_vtu(const std::string &path, const Mesh &mesh, Compression compression) {
  write_vtu_with_state(path, mesh, compression, nullptr);
}

// libdeflate's level for zlib output: 3 made the 4D benchmark's file (5.2 M
// pentatopes) 72.9 MB in 1.58 s of writing, where zlib's level 1 made 74.8
// MB in 2.2-2.5 s and libdeflate's level 1 95.8 MB in 1.62 s.
constexpr int kZlibLevel = 3;

void write_vtu_with_state(const std::string &path, const Mesh &mesh, Compression compression,
                          const StateArrays *state) {
  check_mesh_for_writing(path, mesh);
  write_vtu_native(path, mesh, compression, kZlibLevel, state);
}

} // namespace bisect
