// Extrusion of a 3D mesh into 4D space-time by 4D Delaunay (seed 000 §5.2),
// and of a coloured 2D or 3D mesh by its colouring (seed 001 Def. 1).
#pragma once

#include "bisect/mesh.hpp"

#include <cstdint>
#include <vector>

namespace bisect {

// Embeds copies of the points of the tetrahedral mesh `mesh3` at every time
// slice t of `slices` (strictly ascending, at least 2 values) as (x, y, z, t)
// and triangulates the 4D point set with Qhull's Delaunay triangulation.
// Vertices: slice 0's points, then slice 1's, ...; point data is copied per
// slice; cell data is dropped; every cell is positively oriented; unmarked.
//
// The Delaunay triangulation fills the convex hull of the points, which is
// the prism domain(mesh3) x [t0, tM] only when the 3D domain is convex. The
// total 4D volume is compared with volume(mesh3) * (tM - t0) and InputError
// is thrown when they differ by more than 1e-9 relative. The points of the
// prism are heavily cospherical (every lattice hypercube); ties are broken by
// a tiny deterministic perturbation of the paraboloid lift, so the result is
// a Delaunay (regular) triangulation of the exact points with no flat cell.
// Throws InputError for a non-3D mesh, bad slices or a non-convex domain.
// With `fill_hull` a non-convex domain is accepted: the result then fills the
// convex hull of the points (seed 000 §5.2 does this for a faceted octant).
Mesh extrude_delaunay(const Mesh &mesh3, const std::vector<double> &slices, bool fill_hull = false);

// The Delaunay triangulation of a point set (dim values per point, dim 2..4)
// through Qhull's lower hull of the paraboloid lift, with cospherical ties
// broken by a deterministic perturbation far below `spacing` (a lower bound
// on the distance between two points). Every cell positively oriented,
// unmarked; flat cells dropped. Throws InputError for too few or too close
// points.
Mesh delaunay(int dim, std::vector<double> coords, double spacing);

// Extrusion by colour (seed 001 Def. 1, eq. 5 and eq. 9), for a triangle or
// tetrahedral mesh (n = 2 or 3) with a proper colouring (colour.hpp; colour
// k is the paper's label "ABCD"[k]) and time slices s0 < ... < sM.
//
// Vertex v at slice s becomes vertex s * nv + v at (x_v, t_s): time is the
// last coordinate. Order the vertices of a prism cell x [s_i, s_i+1] by
// "slice first, then colour n, ..., 1, 0" (the paper's D < C < B < A):
//     (x_n, ..., x_1, x_0, x'_n, ..., x'_1, x'_0)     x_k of colour k, ' = upper
// Its n+1 windows of n+1 consecutive entries are the prism's simplices, each
// stored as that window: the Maubach tuple with tag n+1, Stage Maubach, and
// the mesh's marking is Marking::Sorted (the `sorted` rule under this vertex
// order). For n = 3 these are eq. 5 with Stevenson's type-0 tags of eq. 9,
//     (D,C,B,A,D') (C,B,A,D',C') (B,A,D',C',B') (A,D',C',B',A'),
// since Stevenson's (x0..x4)_0 and Maubach's (x0..x4)_4 have the same
// descendants. The same rule one dimension down (2D + time -> tetrahedra):
//     (C,B,A,C') (B,A,C',B') (A,C',B',A').
// Every face of a prism is cut by the order restricted to it, so neighbours
// agree and the mesh is conforming; the tags are consistent in Stevenson's
// sense, so refinement needs no Stage 1.
//
// Point data is copied to every slice and the point array `slice` (the slice
// index 0..M) is added; cell data is inherited by the prism's cells (the
// bisect:* state arrays of the input are dropped). Cells are not reoriented:
// encode_state orients them when the mesh is written. Throws InputError for
// a mesh that is not 2D or 3D, bad slices, or a colouring that is not proper.
Mesh extrude_coloured(const Mesh &mesh, const std::vector<std::uint8_t> &colour,
                      const std::vector<double> &slices);

} // namespace bisect
