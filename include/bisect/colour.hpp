// Vertex colourings of triangle and tetrahedral meshes (seed 001 §2-3): every
// cell's n+1 vertices get n+1 different colours 0..n. Space-time extrusion
// (extrude.hpp) orders every prism's vertices by such a colouring so that the
// pentatopes (or tetrahedra, for 2D+t) are consistently tagged from the start.
//
// Colour k is the paper's label "ABCD"[k]: 0 = A, 1 = B, 2 = C, 3 = D. The
// barycentric subdivision colours vertices by kind in that order: original
// vertices A, edge centres B, face centres C (3D), cell centres D (3D; C in 2D).
#pragma once

#include "bisect/mesh.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bisect {

// The point array holding a colouring (1 component, whole numbers 0..dim).
inline constexpr const char *kColourArray = "colour";

struct Colouring {
  bool ok = false;
  std::vector<std::uint8_t> colour; // per vertex, 0..dim; 0 for unused vertices
  std::size_t components = 0;       // facet-connected components of the cells
  std::string why;                  // one line when !ok
};

// Finds a proper (dim+1)-colouring of a 2D or 3D mesh by propagation across
// facets: the first cell of each facet-connected component takes colours 0..n
// in tuple order, and every neighbour across a facet is forced (its vertex
// opposite the facet takes the one colour the facet lacks). The colouring of a
// component is therefore unique up to a permutation of the colours, and a
// conflict proves that the component has none; `why` names the vertex and,
// when there is one, an interior edge (3D) or vertex (2D) with an odd number
// of cells around it, the usual obstruction. Components that touch only at
// vertices or edges are then reconciled by a small search over the colour
// permutations of each component. O(cells) with a facet hash table.
// Throws std::invalid_argument for a mesh that is not 2D or 3D.
Colouring colour_mesh(const Mesh &mesh);

// Empty when every cell's vertices have different colours in 0..dim;
// otherwise one line naming the first offending cell.
std::string check_colouring(const Mesh &mesh, const std::vector<std::uint8_t> &colour);

// The point array `colour` of the mesh as per-vertex colours, or nullopt when
// the mesh has no such array or when some vertex has kNoLabel (-1: made by
// refinement or slicing after the colouring was written). Throws InputError (without a file name)
// when the array has several components or values that are not whole numbers in 0..dim. Does not
// check that the colouring is proper.
std::optional<std::vector<std::uint8_t>> colour_array(const Mesh &mesh);

// Stores `colour` as the point array `colour` (replacing an existing one).
void set_colour_array(Mesh &mesh, const std::vector<std::uint8_t> &colour);

// Barycentric subdivision of a 2D or 3D mesh: each cell becomes one cell per
// ordering (v, edge centre, [face centre,] cell centre) of its vertices, 6 per
// triangle and 24 per tetrahedron, positively oriented and unmarked. The
// original vertices keep their ids; edge centres, face centres and cell
// centres follow. The result always carries a proper colouring by vertex kind
// (the point array `colour` and `*colour` when given). Cell data is inherited
// by the sub-cells (the bisect:* state arrays are dropped); point data is
// interpolated linearly (a centre gets the mean of its simplex's vertices),
// except a `colour` array of the input, which is replaced.
Mesh barycentric_subdivision(const Mesh &mesh, std::vector<std::uint8_t> *colour = nullptr);

} // namespace bisect
