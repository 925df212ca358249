// Small meshes made from nothing: single simplices and Freudenthal-Kuhn cubes.
//
// Kuhn/Freudenthal: H. Freudenthal, "Simplizialzerlegungen von beschraenkter
// Flachheit", Ann. Math. 43 (1942); every cube is cut into dim! simplices along
// its main diagonal, one per permutation of the axes.
#include "bisect/generate.hpp"

#include "bisect/error.hpp"
#include "bisect/measure.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace bisect {
namespace {

void check_dimension(int dim) {
  if (dim < 2 || dim > 4)
    throw UsageError("unsupported dimension " + std::to_string(dim) + " (expected 2, 3 or 4)");
}

// Unit-edge equilateral simplex built one vertex at a time: vertex k sits
// above the centroid of vertices 0..k-1 (which span the first k-1 axes), at
// the height that makes its distance to vertex 0 equal to one. The edge
// matrix is upper triangular with a positive diagonal, so det > 0.
std::vector<double> equilateral_points(int dim) {
  std::vector<double> p((dim + 1) * dim, 0.0);
  for (int k = 1; k <= dim; ++k) {
    double *v = &p[k * dim];
    for (int i = 0; i < k - 1; ++i) {
      double c = 0;
      for (int j = 0; j < k; ++j)
        c += p[j * dim + i];
      v[i] = c / k;
    }
    double r2 = 0; // squared distance from the centroid to vertex 0
    for (int i = 0; i < k - 1; ++i)
      r2 += v[i] * v[i];
    v[k - 1] = std::sqrt(1.0 - r2);
  }
  return p;
}

std::vector<double> cartesian_points(int dim) {
  std::vector<double> p((dim + 1) * dim, 0.0);
  for (int k = 1; k <= dim; ++k)
    p[k * dim + (k - 1)] = 1.0;
  return p;
}

// The documented perturbation: std::mt19937_64 seeded with `seed`; for each
// vertex in order and each coordinate in order one draw u = (r >> 11) * 2^-53
// in [0,1), and the coordinate moves by 0.3 * (2u - 1). A whole simplex is
// drawn again (continuing the same stream) until its mean ratio exceeds 0.2.
// The mapping from r to u is written out (not std::uniform_real_distribution)
// so the result is identical across standard libraries.
std::vector<double> random_points(int dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const std::vector<double> base = cartesian_points(dim);
  for (;;) {
    std::vector<double> p = base;
    for (double &x : p) {
      const double u = double(rng() >> 11) * 0x1.0p-53;
      x += 0.3 * (2.0 * u - 1.0);
    }
    if (mean_ratio(p.data(), dim) > 0.2)
      return p;
  }
}

Mesh single_cell(int dim, std::vector<double> points) {
  Mesh mesh;
  mesh.dim = dim;
  mesh.coords = std::move(points);
  for (int k = 0; k <= dim; ++k)
    mesh.cells.push_back(VertexId(k));
  orient_positively(mesh, mesh.cells.data());
  return mesh;
}

} // namespace

Mesh generate_simplex(int dim, SimplexShape shape, std::uint64_t seed) {
  check_dimension(dim);
  switch (shape) {
  case SimplexShape::Equilateral:
    return single_cell(dim, equilateral_points(dim));
  case SimplexShape::Cartesian:
    return single_cell(dim, cartesian_points(dim));
  case SimplexShape::Random:
    return single_cell(dim, random_points(dim, seed));
  }
  throw UsageError("unknown simplex shape");
}

// Vertex (i_0, ..., i_{dim-1}) of the (k+1)^dim lattice has id
// sum_j i_j (k+1)^j and coordinates lo + (hi - lo) i_j / k. In the cube with
// lowest corner c and for an axis permutation p the simplex is
// x_0 = c, x_{m+1} = x_m + e_{p[m]}; all cubes share the diagonal direction,
// so faces match across cubes.
Mesh generate_kuhn(int dim, int k, double lo, double hi) {
  check_dimension(dim);
  if (k < 1)
    throw UsageError("kuhn: k must be at least 1");
  if (!(hi > lo))
    throw UsageError("kuhn: need lo < hi");
  Mesh mesh;
  mesh.dim = dim;
  const std::size_t side = std::size_t(k) + 1;
  std::size_t nv = 1, ncubes = 1;
  for (int d = 0; d < dim; ++d)
    nv *= side, ncubes *= std::size_t(k);
  std::vector<std::size_t> stride(dim);
  for (int d = 0; d < dim; ++d)
    stride[d] = d == 0 ? 1 : stride[d - 1] * side;
  if (nv > std::size_t(kNoVertex))
    throw UsageError("kuhn: " + std::to_string(nv) +
                     " vertices, more than 32-bit ids allow (fewer --cells)");

  mesh.coords.resize(nv * dim);
  for (std::size_t v = 0; v < nv; ++v)
    for (int d = 0; d < dim; ++d) {
      const std::size_t i = (v / stride[d]) % side;
      // Exact at both ends of the interval.
      mesh.coords[v * dim + d] = i == std::size_t(k) ? hi : lo + (hi - lo) * double(i) / k;
    }

  std::vector<std::vector<int>> perms;
  std::vector<int> perm(dim);
  for (int d = 0; d < dim; ++d)
    perm[d] = d;
  do
    perms.push_back(perm);
  while (std::next_permutation(perm.begin(), perm.end()));

  mesh.cells.reserve(ncubes * perms.size() * (dim + 1));
  std::vector<double> pts((dim + 1) * dim);
  for (std::size_t cube = 0; cube < ncubes; ++cube) {
    std::size_t corner = 0, rest = cube;
    for (int d = 0; d < dim; ++d) {
      corner += (rest % std::size_t(k)) * stride[d];
      rest /= std::size_t(k);
    }
    for (const auto &p : perms) {
      const std::size_t first = mesh.cells.size();
      std::size_t v = corner;
      mesh.cells.push_back(VertexId(v));
      for (int m = 0; m < dim; ++m) {
        v += stride[p[m]];
        mesh.cells.push_back(VertexId(v));
      }
      for (int m = 0; m <= dim; ++m)
        for (int d = 0; d < dim; ++d)
          pts[m * dim + d] = mesh.coords[mesh.cells[first + m] * std::size_t(dim) + d];
      if (signed_volume(pts.data(), dim) < 0)
        std::swap(mesh.cells[first], mesh.cells[first + 1]);
    }
  }
  return mesh;
}

} // namespace bisect
