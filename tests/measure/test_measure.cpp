// Tests for src/measure.cpp: volume, mean ratio, similarity keys.
#include "bisect/generate.hpp"
#include "bisect/measure.hpp"
#include "bisect/threads.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

using namespace bisect;

namespace {

std::vector<double> simplex_points(const Mesh &m) {
  std::vector<double> p((m.dim + 1) * m.dim);
  cell_points(m, 0, p.data());
  return p;
}

// Vertex k of the result is vertex perm[k] of p.
std::vector<double> permuted(const std::vector<double> &p, const std::vector<int> &perm, int dim) {
  std::vector<double> q(p.size());
  for (int k = 0; k <= dim; ++k)
    for (int d = 0; d < dim; ++d)
      q[k * dim + d] = p[perm[k] * dim + d];
  return q;
}

// A random orthogonal matrix (Gram-Schmidt of random columns), row-major.
std::vector<double> random_rotation(int dim, std::mt19937_64 &rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> q(dim * dim);
  for (int j = 0; j < dim; ++j) {
    std::vector<double> v(dim);
    for (double &x : v)
      x = u(rng);
    for (int k = 0; k < j; ++k) {
      double dot = 0;
      for (int i = 0; i < dim; ++i)
        dot += v[i] * q[i * dim + k];
      for (int i = 0; i < dim; ++i)
        v[i] -= dot * q[i * dim + k];
    }
    double norm = 0;
    for (double x : v)
      norm += x * x;
    norm = std::sqrt(norm);
    for (int i = 0; i < dim; ++i)
      q[i * dim + j] = v[i] / norm;
  }
  return q;
}

// x -> s * Q x + t, for every vertex.
std::vector<double> transformed(const std::vector<double> &p, int dim, const std::vector<double> &q,
                                double s, const std::vector<double> &t) {
  std::vector<double> r(p.size());
  for (int k = 0; k <= dim; ++k)
    for (int i = 0; i < dim; ++i) {
      double x = 0;
      for (int j = 0; j < dim; ++j)
        x += q[i * dim + j] * p[k * dim + j];
      r[k * dim + i] = s * x + t[i];
    }
  return r;
}

// Determinant by cofactor expansion (small n only; independent of measure.cpp).
double det_ref(const std::vector<double> &a, int n) {
  if (n == 1)
    return a[0];
  double det = 0;
  for (int j = 0; j < n; ++j) {
    std::vector<double> minor;
    for (int r = 1; r < n; ++r)
      for (int c = 0; c < n; ++c)
        if (c != j)
          minor.push_back(a[r * n + c]);
    det += (j % 2 ? -1 : 1) * a[j] * det_ref(minor, n - 1);
  }
  return det;
}

// Inverse by Gauss-Jordan, row-major.
std::vector<double> inverse_ref(std::vector<double> a, int n) {
  std::vector<double> inv(n * n, 0.0);
  for (int i = 0; i < n; ++i)
    inv[i * n + i] = 1;
  for (int k = 0; k < n; ++k) {
    int p = k;
    for (int i = k + 1; i < n; ++i)
      if (std::abs(a[i * n + k]) > std::abs(a[p * n + k]))
        p = i;
    for (int j = 0; j < n; ++j)
      std::swap(a[k * n + j], a[p * n + j]), std::swap(inv[k * n + j], inv[p * n + j]);
    const double piv = a[k * n + k];
    for (int j = 0; j < n; ++j)
      a[k * n + j] /= piv, inv[k * n + j] /= piv;
    for (int i = 0; i < n; ++i)
      if (i != k) {
        const double f = a[i * n + k];
        for (int j = 0; j < n; ++j)
          a[i * n + j] -= f * a[k * n + j], inv[i * n + j] -= f * inv[k * n + j];
      }
  }
  return inv;
}

// Knupp's q = n |det S|^(2/n) / |S|_F^2 with S = A W^-1, computed literally.
double mean_ratio_by_definition(const std::vector<double> &p, const std::vector<double> &ref,
                                int n) {
  auto edge_matrix = [n](const std::vector<double> &x) {
    std::vector<double> a(n * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        a[i * n + j] = x[(j + 1) * n + i] - x[i];
    return a;
  };
  const std::vector<double> a = edge_matrix(p), winv = inverse_ref(edge_matrix(ref), n);
  std::vector<double> s(n * n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        s[i * n + j] += a[i * n + k] * winv[k * n + j];
  double frob = 0;
  for (double x : s)
    frob += x * x;
  return n * std::pow(std::abs(det_ref(s, n)), 2.0 / n) / frob;
}

std::vector<int> identity(int dim) {
  std::vector<int> perm(dim + 1);
  std::iota(perm.begin(), perm.end(), 0);
  return perm;
}

} // namespace

TEST_CASE(
    "signed volume is 1/n! for the cartesian simplex and flips sign with two swapped vertices",
    "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const std::vector<double> p = simplex_points(generate_simplex(dim, SimplexShape::Cartesian));
  const double fact = dim == 2 ? 2 : dim == 3 ? 6 : 24;
  CHECK(signed_volume(p.data(), dim) == Approx(1.0 / fact));
  std::vector<int> perm = identity(dim);
  std::swap(perm[0], perm[1]);
  CHECK(signed_volume(permuted(p, perm, dim).data(), dim) == Approx(-1.0 / fact));
}

TEST_CASE("mean ratio is 1 for the equilateral simplex and invariant under permutation and scaling",
          "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const std::vector<double> eq = simplex_points(generate_simplex(dim, SimplexShape::Equilateral));
  CHECK(mean_ratio(eq.data(), dim) == Approx(1.0).epsilon(1e-12));

  const std::vector<double> p = simplex_points(generate_simplex(dim, SimplexShape::Random, 7));
  const double q = mean_ratio(p.data(), dim);
  CHECK(q > 0.2);
  CHECK(q < 1.0);
  std::vector<int> perm = identity(dim);
  do {
    CHECK(mean_ratio(permuted(p, perm, dim).data(), dim) == Approx(q).epsilon(1e-12));
  } while (std::next_permutation(perm.begin(), perm.end()));
  std::vector<double> scaled = p;
  for (double &x : scaled)
    x = 1e-3 * x + 5.0;
  CHECK(mean_ratio(scaled.data(), dim) == Approx(q).epsilon(1e-9));
}

TEST_CASE("mean ratio equals Knupp's definition with S = A W^-1 computed literally",
          "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const std::vector<double> ref = simplex_points(generate_simplex(dim, SimplexShape::Equilateral));
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const std::vector<double> p = simplex_points(generate_simplex(dim, SimplexShape::Random, seed));
    CHECK(mean_ratio(p.data(), dim) ==
          Approx(mean_ratio_by_definition(p, ref, dim)).epsilon(1e-10));
  }
  const std::vector<double> c = simplex_points(generate_simplex(dim, SimplexShape::Cartesian));
  CHECK(mean_ratio(c.data(), dim) == Approx(mean_ratio_by_definition(c, ref, dim)).epsilon(1e-10));
}

TEST_CASE("mean ratio tends to 0 for a flattened simplex", "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  std::vector<double> p = simplex_points(generate_simplex(dim, SimplexShape::Equilateral));
  // Push the last vertex onto the hyperplane of the others (its last coordinate is the height).
  const double height = p[dim * dim + dim - 1];
  double previous = 1.0 + 1e-12;
  for (double t : {1.0, 0.5, 0.1, 1e-2, 1e-4, 1e-8, 1e-12}) {
    p[dim * dim + dim - 1] = t * height;
    const double q = mean_ratio(p.data(), dim);
    CHECK(q < previous);
    previous = q;
  }
  CHECK(previous < 1e-4);
  p[dim * dim + dim - 1] = 0;
  CHECK(mean_ratio(p.data(), dim) == 0.0);
}

TEST_CASE("similarity key is invariant under permutation, translation, rotation and scaling",
          "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  std::mt19937_64 rng(42);
  const std::vector<double> p = simplex_points(generate_simplex(dim, SimplexShape::Random, 3));
  const std::vector<long long> key = similarity_key(p.data(), dim);
  REQUIRE(key.size() == std::size_t(dim * (dim + 1) / 2));
  std::vector<int> perm = identity(dim);
  do {
    const std::vector<double> q =
        transformed(permuted(p, perm, dim), dim, random_rotation(dim, rng), 0.37,
                    std::vector<double>(dim, 12.5));
    CHECK(similarity_key(q.data(), dim) == key);
  } while (std::next_permutation(perm.begin(), perm.end()));

  // A different shape has a different key.
  const std::vector<double> c = simplex_points(generate_simplex(dim, SimplexShape::Cartesian));
  CHECK(similarity_key(c.data(), dim) != key);
}

TEST_CASE("similarity classes: a Kuhn mesh is one class; equilateral and cartesian are two",
          "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  CHECK(count_similarity_classes(generate_kuhn(dim, 3, -1.0, 2.0)) == 1);

  Mesh two = generate_simplex(dim, SimplexShape::Equilateral);
  const Mesh cart = generate_simplex(dim, SimplexShape::Cartesian);
  for (VertexId v : cart.cells)
    two.cells.push_back(v + VertexId(two.num_vertices()));
  two.coords.insert(two.coords.end(), cart.coords.begin(), cart.coords.end());
  CHECK(count_similarity_classes(two) == 2);
  CHECK(count_similarity_classes(Mesh{}) == 0);
}

TEST_CASE("quality summary is the min, max and mean of every cell's mean ratio",
          "[measure][quality][2d][3d][4d]") {
  // A Kuhn mesh with its inner points moved, so that the cells differ, and
  // a cell count that is not a multiple of the pass's batch of 16: every
  // cell's mean ratio, taken one by one, gives the same figures to the bit
  // (one block of cells: the same order of summation).
  const int dim = GENERATE(2, 3, 4);
  Mesh m = generate_kuhn(dim, dim == 4 ? 2 : 3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    for (int d = 0; d < dim; ++d) {
      double &x = m.coords[v * std::size_t(dim) + std::size_t(d)];
      if (x > 0 && x < 1)
        x += jitter(rng);
    }
  m.cells.resize(m.cells.size() - std::size_t(dim + 1)); // one cell fewer
  const std::size_t nc = m.num_cells();
  REQUIRE(nc % 16 != 0);
  double lo = 1e300, hi = -1e300, sum = 0;
  std::vector<double> p((dim + 1) * dim);
  for (std::size_t c = 0; c < nc; ++c) {
    cell_points(m, CellId(c), p.data());
    const double q = mean_ratio(p.data(), dim);
    lo = std::min(lo, q);
    hi = std::max(hi, q);
    sum += q;
  }
  const QualitySummary s = quality_summary(m);
  INFO("dim " << dim << ", " << nc << " cells");
  CHECK(lo < hi);
  CHECK(s.min == lo);
  CHECK(s.max == hi);
  CHECK(s.mean == sum / double(nc));
}

TEST_CASE("quality histogram: every cell's mean ratio counted once, the same on any thread count",
          "[measure][quality][threads][3d]") {
  // 3D Kuhn cubes with their inner points moved: ten blocks of cells
  // (16,384 each, the last partial), enough for up to 2 threads (4 each).
  Mesh m = generate_kuhn(3, 30);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (double &x : m.coords)
    if (x > 0 && x < 1)
      x += jitter(rng);
  REQUIRE(m.num_cells() > 9 * 16384);
  const int bins = 7;
  std::vector<std::size_t> counts(bins, 0);
  double lo = 1, hi = 0, sum = 0;
  double p[16];
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    cell_points(m, CellId(c), p);
    const double q = mean_ratio(p, 3);
    lo = std::min(lo, q), hi = std::max(hi, q), sum += q;
    ++counts[std::min(std::size_t(q * bins), std::size_t(bins - 1))];
  }
  QualityHistogram first;
  for (int t : {1, 2, 3}) {
    set_threads(t);
    const QualityHistogram h = quality_histogram(m, bins);
    INFO(t << " threads");
    CHECK(h.counts == counts);
    CHECK(h.summary.min == lo);
    CHECK(h.summary.max == hi);
    CHECK(h.summary.mean == Approx(sum / double(m.num_cells())).epsilon(1e-13));
    if (t == 1)
      first = h;
    CHECK(h.summary.mean == first.summary.mean); // to the bit
  }
  set_threads(0);
  const QualityHistogram none = quality_histogram(Mesh{}, 3);
  CHECK(none.counts == std::vector<std::size_t>(3, 0));
  CHECK(none.summary.min == 1);
  CHECK(none.summary.max == 0);
}

TEST_CASE("quality summary of a Kuhn mesh: every cell has the same mean ratio",
          "[measure][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = generate_kuhn(dim, 2);
  const QualitySummary s = quality_summary(m);
  std::vector<double> p((dim + 1) * dim);
  cell_points(m, 0, p.data());
  const double q = mean_ratio(p.data(), dim);
  CHECK(s.min == Approx(q));
  CHECK(s.max == Approx(q));
  CHECK(s.mean == Approx(q));
  CHECK(q > 0);
  CHECK(q < 1);
}

TEST_CASE("cell_points copies the cell's vertices in tuple order", "[measure][2d]") {
  Mesh m;
  m.dim = 2;
  m.coords = {0, 0, 1, 0, 0, 1, 5, 6};
  m.cells = {3, 1, 2};
  double p[6];
  cell_points(m, 0, p);
  CHECK(std::vector<double>(p, p + 6) == std::vector<double>{5, 6, 1, 0, 0, 1});
}
