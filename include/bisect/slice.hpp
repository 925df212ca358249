// Sections of 4D meshes by the hyperplanes x[axis] = value (e.g. t = const),
// and of 3D meshes by planes (the time slices of a 2D+t mesh).
#pragma once

#include "bisect/mesh.hpp"

namespace bisect {

// Returns the section of a 4D mesh by the hyperplane x[axis] = value as a 3D
// tetrahedral Mesh (coordinates: the three other axes, in order), with point
// data interpolated linearly and cell data copied from the cut pentatope.
//
// The output is conforming when the input is: cut points are shared between
// pentatopes through their edge (or, for a vertex on the hyperplane, through
// the vertex), and every cut polytope (tetrahedron, square pyramid or
// triangular prism) is split by the pulling triangulation from its
// smallest-key vertex, which agrees on every shared face. A cut point's key
// is its edge's two ends, ranked by their coordinates (lexicographically),
// and it is interpolated from the lower-ranked end: the section depends on
// the cells alone, not on the vertices' numbering. Pentatopes touching
// the hyperplane only in a vertex, edge or triangle contribute nothing; a
// tetrahedral facet lying in the hyperplane is produced once (from the
// pentatope on the side x >= value when there is one). Tets are positively
// oriented, the mesh is unmarked, unused vertices are absent, and the
// `bisect:*` state arrays are not copied. A hyperplane missing the mesh gives
// an empty mesh (dim 3, no vertices, no cells).
//
// A 3D tetrahedral mesh gives the same for one dimension less: a conforming
// 2D triangle mesh (cut triangles and quadrilaterals, the latter split by
// the diagonal through the smallest-key cut point).
//
// Throws InputError when mesh4.dim is not 3 or 4 or axis is not in 0..dim-1.
Mesh slice_mesh(const Mesh &mesh4, int axis, double value);

} // namespace bisect
