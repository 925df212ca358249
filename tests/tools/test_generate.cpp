// Tests for src/generate.cpp: single simplices and Freudenthal-Kuhn cubes.
#include "bisect/check.hpp"
#include "bisect/generate.hpp"
#include "bisect/measure.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace bisect;

namespace {

double factorial(int n) {
  return n <= 1 ? 1 : n * factorial(n - 1);
}

double cell_volume(const Mesh &m, CellId c) {
  std::vector<double> p((m.dim + 1) * m.dim);
  cell_points(m, c, p.data());
  return signed_volume(p.data(), m.dim);
}

bool unmarked(const Mesh &m) {
  return m.stage.empty() && m.tag.empty();
}

} // namespace

TEST_CASE("equilateral simplex has unit edges, is positively oriented and unmarked",
          "[generate][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = generate_simplex(dim, SimplexShape::Equilateral);
  REQUIRE(m.num_cells() == 1);
  REQUIRE(m.num_vertices() == std::size_t(dim + 1));
  CHECK(unmarked(m));
  for (int i = 0; i <= dim; ++i)
    for (int j = i + 1; j <= dim; ++j) {
      double l2 = 0;
      for (int d = 0; d < dim; ++d) {
        const double x = m.point(VertexId(i))[d] - m.point(VertexId(j))[d];
        l2 += x * x;
      }
      CHECK(std::sqrt(l2) == Approx(1.0).epsilon(1e-14));
    }
  CHECK(cell_volume(m, 0) > 0);
}

TEST_CASE("cartesian simplex is the origin and the unit vectors, volume 1/n!",
          "[generate][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = generate_simplex(dim, SimplexShape::Cartesian);
  CHECK(unmarked(m));
  CHECK(cell_volume(m, 0) == Approx(1.0 / factorial(dim)));
  std::vector<double> expected((dim + 1) * dim, 0.0);
  for (int k = 1; k <= dim; ++k)
    expected[k * dim + k - 1] = 1;
  CHECK(m.coords == expected);
}

TEST_CASE("random simplex is deterministic per seed, positive and of mean ratio above 0.2",
          "[generate][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Mesh a = generate_simplex(dim, SimplexShape::Random, seed);
    const Mesh b = generate_simplex(dim, SimplexShape::Random, seed);
    CHECK(a.coords == b.coords);
    CHECK(a.cells == b.cells);
    CHECK(cell_volume(a, 0) > 0);
    std::vector<double> p((dim + 1) * dim);
    cell_points(a, 0, p.data());
    CHECK(mean_ratio(p.data(), dim) > 0.2);
    const Mesh cart = generate_simplex(dim, SimplexShape::Cartesian);
    for (std::size_t i = 0; i < a.coords.size(); ++i)
      CHECK(std::abs(a.coords[i] - cart.coords[i]) <= 0.3);
  }
  CHECK(generate_simplex(dim, SimplexShape::Random, 1).coords !=
        generate_simplex(dim, SimplexShape::Random, 2).coords);
}

TEST_CASE(
    "kuhn: [0,1]^4 with k=1 is 24 pentatopes of total volume 1 and passes the conformity check",
    "[generate][4d]") {
  const Mesh m = generate_kuhn(4, 1);
  CHECK(m.num_cells() == 24);
  CHECK(m.num_vertices() == 16);
  CHECK(unmarked(m));
  const Invariants inv = measure_invariants(m);
  CHECK(inv.volume == Approx(1.0).epsilon(1e-14));
  CHECK(inv.boundary_measure == Approx(8.0).epsilon(1e-14));
  CHECK(inv.euler == 1);
  const CheckResult r = check_conformity(m, &inv);
  CHECK(r.ok);
  CHECK(r.failure.empty());
}

TEST_CASE("kuhn meshes in 2D/3D/4D are conforming with Euler characteristic 1",
          "[generate][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const int k = GENERATE(1, 2, 3);
  const Mesh m = generate_kuhn(dim, k, -1.0, 1.0);
  const Invariants inv = measure_invariants(m);
  CHECK(inv.euler == 1);
  CHECK(inv.volume == Approx(std::pow(2.0, dim)));
  CHECK(inv.boundary_measure == Approx(2 * dim * std::pow(2.0, dim - 1)));
  // A cube face of k^(dim-1) squares cut into (dim-1)! simplices each, 2 dim faces.
  CHECK(inv.boundary_facets == std::size_t(2 * dim * std::pow(k, dim - 1) * factorial(dim - 1)));
  const CheckResult r = check_conformity(m, &inv);
  INFO(r.failure);
  CHECK(r.ok);
  Mesh copy = m;
  CHECK_NOTHROW(prepare_input(copy, "kuhn"));
  CHECK(copy.cells == m.cells); // already positively oriented
}

TEST_CASE("kuhn: vertices lie on the lattice, cells are positive and unmarked",
          "[generate][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const int k = 3;
  const double lo = 0.5, hi = 2.0;
  const Mesh m = generate_kuhn(dim, k, lo, hi);
  CHECK(unmarked(m));
  CHECK(m.num_vertices() == std::size_t(std::pow(k + 1, dim)));
  CHECK(m.num_cells() == std::size_t(std::pow(k, dim) * factorial(dim)));
  for (double x : m.coords) {
    const double t = (x - lo) / (hi - lo) * k;
    CHECK(std::abs(t - std::round(t)) < 1e-12);
    CHECK(x >= lo);
    CHECK(x <= hi);
  }
  const double h = (hi - lo) / k;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    CHECK(cell_volume(m, CellId(c)) == Approx(std::pow(h, dim) / factorial(dim)));
}

TEST_CASE("generators reject unsupported arguments", "[generate]") {
  CHECK_THROWS(generate_simplex(5, SimplexShape::Equilateral));
  CHECK_THROWS(generate_kuhn(1, 2));
  CHECK_THROWS(generate_kuhn(3, 0));
  CHECK_THROWS(generate_kuhn(3, 2, 1.0, 1.0));
}
