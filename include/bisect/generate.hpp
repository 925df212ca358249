// Small meshes made from nothing: single simplices and Kuhn cubes.
#pragma once

#include "bisect/mesh.hpp"

#include <cstdint>
#include <string>

namespace bisect {

enum class SimplexShape { Equilateral, Cartesian, Random };

// One simplex of dimension `dim` (2, 3, 4), positively oriented, unmarked.
// Equilateral: unit edge length. Cartesian: the origin and the unit vectors.
// Random: the cartesian simplex with every coordinate perturbed by up to 0.3
// (deterministic for a given seed), re-drawn until its mean ratio > 0.2.
Mesh generate_simplex(int dim, SimplexShape shape, std::uint64_t seed = 1);

// The Freudenthal-Kuhn subdivision of [lo,hi]^dim into k^dim cubes of dim!
// simplices each, conforming, positively oriented, unmarked.
Mesh generate_kuhn(int dim, int k, double lo = 0.0, double hi = 1.0);

} // namespace bisect
