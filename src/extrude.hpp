// Extrusion of a 3D mesh into 4D space-time by 4D Delaunay (seed 000 §5.2).
#pragma once

#include "mesh.hpp"

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
Mesh extrude_delaunay(const Mesh &mesh3, const std::vector<double> &slices);

} // namespace bisect
