// How messages name vertices, cells and faces: the one place that turns ids
// into the numbering of the file the mesh came from (Mesh::numbering).
//  - by default, 0-based indices: "vertex 12", "cell 5", "facet (3, 9, 11)";
//  - for a .msh input, Gmsh's tags: "node 205", "element 17",
//    "facet of nodes (4, 10, 12)".
// Only the formatting of a finding goes through here, never a hot loop.
#pragma once

#include "bisect/mesh.hpp"

#include <string>

namespace bisect {

// True when `mesh.numbering` holds Gmsh tags sized for this mesh.
inline bool names_by_tag(const Mesh &mesh) {
  const FileNumbering &n = mesh.numbering;
  return n.gmsh && n.vertices == mesh.num_vertices() && n.cells == mesh.num_cells();
}

// "vertex" / "vertices", or "node" / "nodes".
inline const char *vertex_word(const Mesh &mesh, bool plural = false) {
  if (names_by_tag(mesh))
    return plural ? "nodes" : "node";
  return plural ? "vertices" : "vertex";
}

// "cell" / "cells", or "element" / "elements".
inline const char *cell_word(const Mesh &mesh, bool plural = false) {
  if (names_by_tag(mesh))
    return plural ? "elements" : "element";
  return plural ? "cells" : "cell";
}

// The number of vertex v: its index, or its node tag.
inline std::string vertex_number(const Mesh &mesh, VertexId v) {
  return std::to_string(names_by_tag(mesh) ? mesh.numbering.node(v) : std::uint64_t(v));
}

// The number of cell c: its index, or its element tag.
inline std::string cell_number(const Mesh &mesh, CellId c) {
  return std::to_string(names_by_tag(mesh) ? mesh.numbering.element(c) : std::uint64_t(c));
}

// "vertex 12" or "node 205".
inline std::string vertex_name(const Mesh &mesh, VertexId v) {
  return std::string(vertex_word(mesh)) + " " + vertex_number(mesh, v);
}

// "cell 5" or "element 17".
inline std::string cell_name(const Mesh &mesh, CellId c) {
  return std::string(cell_word(mesh)) + " " + cell_number(mesh, c);
}

// "cells 5 and 9" or "elements 17 and 21".
inline std::string cell_pair_name(const Mesh &mesh, CellId a, CellId b) {
  return std::string(cell_word(mesh, true)) + " " + cell_number(mesh, a) + " and " +
         cell_number(mesh, b);
}

// The vertices of a face after its kind ("facet", "edge", ...): "(3, 9, 11)"
// or "of nodes (4, 10, 12)".
inline std::string face_ids(const Mesh &mesh, const VertexId *ids, int count) {
  std::string s = names_by_tag(mesh) ? "of nodes (" : "(";
  for (int i = 0; i < count; ++i)
    s += (i ? ", " : "") + vertex_number(mesh, ids[i]);
  return s + ")";
}

} // namespace bisect
