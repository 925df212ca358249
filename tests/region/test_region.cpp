// Tests for region.cpp: the touches() predicate of every region type (exact
// cases built by hand, and randomized checks against dense sampling of the
// simplex), bounds(), and the errors of the JSON spec reader.
#include "bisect/region.hpp"

#include "bisect/generate.hpp"
#include "bisect/measure.hpp"

#include "bisect/mesh.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

using namespace bisect;

namespace {

std::unique_ptr<Region> spec(const std::string &text, int dim) {
  return parse_region(text, dim, "test.json");
}

bool touches(const Region &r, const std::vector<double> &verts, int dim) {
  REQUIRE(int(verts.size()) == dim * (dim + 1));
  return r.touches(verts.data(), dim);
}

// The points of the simplex whose barycentric coordinates are multiples of
// 1/n (vertices included). Every point of the simplex lies within
// lattice_spacing() of one of them.
std::vector<double> lattice(const std::vector<double> &verts, int dim, int n) {
  std::vector<double> out;
  std::vector<int> a(dim + 1, 0);
  std::function<void(int, int)> rec = [&](int i, int left) {
    if (i == dim) {
      a[dim] = left;
      for (int k = 0; k < dim; ++k) {
        double x = 0;
        for (int j = 0; j <= dim; ++j)
          x += a[j] * verts[j * dim + k];
        out.push_back(x / n);
      }
      return;
    }
    for (int v = 0; v <= left; ++v) {
      a[i] = v;
      rec(i + 1, left - v);
    }
  };
  rec(0, n);
  return out;
}

double diameter(const std::vector<double> &verts, int dim) {
  double d = 0;
  for (int i = 0; i <= dim; ++i)
    for (int j = 0; j <= dim; ++j) {
      double s = 0;
      for (int k = 0; k < dim; ++k)
        s += std::pow(verts[i * dim + k] - verts[j * dim + k], 2);
      d = std::max(d, std::sqrt(s));
    }
  return d;
}

// Rounding barycentric coordinates to the lattice moves each by < 1/n.
double lattice_spacing(const std::vector<double> &verts, int dim, int n) {
  return (dim + 1) * diameter(verts, dim) / n;
}

double norm_to(const double *x, const std::vector<double> &c) {
  double s = 0;
  for (std::size_t k = 0; k < c.size(); ++k)
    s += (x[k] - c[k]) * (x[k] - c[k]);
  return std::sqrt(s);
}

std::string vec_json(const std::vector<double> &v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i)
    s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

// A random simplex of size up to ~0.6 somewhere in [-0.2, 1.2]^dim.
std::vector<double> random_simplex(std::mt19937_64 &rng, int dim) {
  std::uniform_real_distribution<double> u(-0.2, 1.2), off(-1, 1), size(0.02, 0.6);
  std::vector<double> base(dim), verts(dim * (dim + 1));
  for (double &b : base)
    b = u(rng);
  const double s = size(rng);
  for (int i = 0; i <= dim; ++i)
    for (int k = 0; k < dim; ++k)
      verts[i * dim + k] = base[k] + s * off(rng);
  return verts;
}

std::vector<double> random_point(std::mt19937_64 &rng, int dim, double a, double b) {
  std::uniform_real_distribution<double> u(a, b);
  std::vector<double> p(dim);
  for (double &x : p)
    x = u(rng);
  return p;
}

struct Tally {
  int selected = 0, rejected = 0, sampled_hits = 0;
};

} // namespace

// ---------------------------------------------------------------------------
// sphere

TEST_CASE(
    "sphere: a tet straddling the surface touches, one strictly inside or far outside does not",
    "[region][3d]") {
  auto surface = spec(R"({"type":"sphere","center":[0,0,0],"radius":1})", 3);
  auto ball = spec(R"({"type":"sphere","center":[0,0,0],"radius":1,"solid":true})", 3);
  const std::vector<double> straddling = {0.9, 0, 0, 1.1, 0, 0, 1, 0.1, 0, 1, 0, 0.1};
  const std::vector<double> inside = {-0.1, -0.1, -0.1, 0.2, 0, 0, 0, 0.2, 0, 0, 0, 0.2};
  const std::vector<double> outside = {2, 2, 2, 2.5, 2, 2, 2, 2.5, 2, 2, 2, 2.5};
  const std::vector<double> containing = {-5, -5, -5, 10, -5, -5, -5, 10, -5, -5, -5, 10};
  CHECK(touches(*surface, straddling, 3));
  CHECK_FALSE(touches(*surface, inside, 3));
  CHECK_FALSE(touches(*surface, outside, 3));
  CHECK(touches(*surface, containing, 3)); // no vertex near the sphere, yet the sphere is inside
  CHECK(touches(*ball, straddling, 3));
  CHECK(touches(*ball, inside, 3));
  CHECK_FALSE(touches(*ball, outside, 3));
  CHECK(touches(*ball, containing, 3));
}

TEST_CASE("sphere: a vertex exactly on the surface touches", "[region][2d]") {
  auto circle = spec(R"({"type":"sphere","center":[0,0],"radius":1})", 2);
  CHECK(touches(*circle, {1, 0, 2, 0, 2, 1}, 2));
  CHECK(touches(*circle, {1, 0, 0, 0, 0.5, 0.5}, 2));
}

TEST_CASE("sphere: exact min distance to an edge interior (an edge passing through the disc, no "
          "vertex inside)",
          "[region][2d]") {
  // The edge y = 0.1, -1 <= x <= 1 passes 0.1 from the centre.
  const std::vector<double> tri = {-1, 0.1, 1, 0.1, 0, 5};
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0],"radius":0.2})", 2), tri, 2));
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0],"radius":0.1})", 2), tri, 2));
  CHECK_FALSE(touches(*spec(R"({"type":"sphere","center":[0,0],"radius":0.099})", 2), tri, 2));
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0],"radius":0.2,"solid":true})", 2), tri, 2));
  CHECK_FALSE(
      touches(*spec(R"({"type":"sphere","center":[0,0],"radius":0.099,"solid":true})", 2), tri, 2));
}

TEST_CASE("sphere: exact min distance to a face interior (a face passing through the ball, no "
          "vertex inside)",
          "[region][3d]") {
  // The face z = 0.1 passes 0.1 above the centre; its nearest point (0,0,0.1)
  // is inside the face, far from every edge.
  const std::vector<double> tet = {-1, -1, 0.1, 2, -1, 0.1, -1, 2, 0.1, 0, 0, 3};
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0,0],"radius":0.2})", 3), tet, 3));
  CHECK_FALSE(touches(*spec(R"({"type":"sphere","center":[0,0,0],"radius":0.099})", 3), tet, 3));
  CHECK_FALSE(touches(*spec(R"({"type":"sphere","center":[0,0,0],"radius":0.099,"solid":true})", 3),
                      tet, 3));
}

TEST_CASE("sphere: exact min distance to a facet interior of a pentatope", "[region][4d]") {
  // The facet t = 0.1 (a tet) holds (0,0,0,0.1); every vertex is far away.
  const std::vector<double> pent = {-1, -1,  -1, 0.1, 3, -1,  -1, 0.1, -1, 3,
                                    -1, 0.1, -1, -1,  3, 0.1, 0,  0,   0,  4};
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0,0,0],"radius":0.15})", 4), pent, 4));
  CHECK_FALSE(touches(*spec(R"({"type":"sphere","center":[0,0,0,0],"radius":0.099})", 4), pent, 4));
  // The centre inside the pentatope: distance 0.
  CHECK(touches(*spec(R"({"type":"sphere","center":[0,0,0,1],"radius":0.01,"solid":true})", 4),
                pent, 4));
}

// Never misses: if the lattice samples of the simplex lie on both sides of the
// sphere (or one lies in the ball), touches() is true. Exact: if touches() is
// true, the samples come within one lattice spacing of the surface (ball).
static void check_sphere_against_sampling(int dim, bool solid) {
  std::mt19937_64 rng(1234 + dim + (solid ? 100 : 0));
  std::uniform_real_distribution<double> radius(0.05, 0.9);
  const int n = dim == 4 ? 10 : 16;
  Tally tally;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::vector<double> c = random_point(rng, dim, -0.3, 1.3);
    const double r = radius(rng);
    auto region = spec(R"({"type":"sphere","center":)" + vec_json(c) + R"(,"radius":)" +
                           std::to_string(r) + (solid ? R"(,"solid":true})" : "}"),
                       dim);
    const double rr = std::stod(std::to_string(r)); // the radius as parsed
    const std::vector<double> verts = random_simplex(rng, dim);
    const std::vector<double> pts = lattice(verts, dim, n);
    double dmin = 1e300, dmax = 0;
    for (std::size_t p = 0; p < pts.size(); p += dim) {
      const double d = norm_to(&pts[p], c);
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
    }
    const bool sampled = solid ? dmin <= rr : dmin <= rr && rr <= dmax;
    const bool got = touches(*region, verts, dim);
    INFO("trial " << trial);
    if (sampled)
      CHECK(got);
    if (got) {
      const double h = lattice_spacing(verts, dim, n);
      CHECK(dmin <= rr + h);
      if (!solid)
        CHECK(dmax >= rr); // the max is at a vertex, which is sampled
    }
    tally.sampled_hits += sampled;
    (got ? tally.selected : tally.rejected)++;
  }
  // The random cases exercise both answers.
  CHECK(tally.selected > 100);
  CHECK(tally.rejected > 100);
}

TEST_CASE(
    "sphere surface: never misses a cell that dense sampling shows crossing it, and is exact (2D)",
    "[region][2d]") {
  check_sphere_against_sampling(2, false);
}
TEST_CASE(
    "sphere surface: never misses a cell that dense sampling shows crossing it, and is exact (3D)",
    "[region][3d]") {
  check_sphere_against_sampling(3, false);
}
TEST_CASE(
    "sphere surface: never misses a cell that dense sampling shows crossing it, and is exact (4D)",
    "[region][4d]") {
  check_sphere_against_sampling(4, false);
}
TEST_CASE("solid ball: never misses a cell that dense sampling shows inside it, and is exact (2D)",
          "[region][2d]") {
  check_sphere_against_sampling(2, true);
}
TEST_CASE("solid ball: never misses a cell that dense sampling shows inside it, and is exact (3D)",
          "[region][3d]") {
  check_sphere_against_sampling(3, true);
}
TEST_CASE("solid ball: never misses a cell that dense sampling shows inside it, and is exact (4D)",
          "[region][4d]") {
  check_sphere_against_sampling(4, true);
}

// ---------------------------------------------------------------------------
// hemisphere

// Seed 002 Section 5.2: sphere r = 1 at (1/2,1/2,1/2), the part with x >= 1/2.
static const char *kPaperHemisphere =
    R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,"normal":[1,0,0],"offset":0.5})";

static std::vector<double> small_tet_at(double x, double y, double z, double h = 0.05) {
  return {x - h, y - h, z - h, x + h, y - h, z - h, x - h, y + h, z - h, x - h, y - h, z + h};
}

TEST_CASE("hemisphere: cells on the excluded side are not selected", "[region][3d]") {
  auto h = spec(kPaperHemisphere, 3);
  CHECK(touches(*h, small_tet_at(1.5, 0.5, 0.5), 3));        // on the kept half
  CHECK_FALSE(touches(*h, small_tet_at(-0.5, 0.5, 0.5), 3)); // on the sphere, excluded half
  CHECK(touches(*h, small_tet_at(0.5, 1.5, 0.5), 3));        // on the rim, straddling the plane
  CHECK_FALSE(touches(*h, small_tet_at(1.0, 0.5, 0.5), 3));  // inside the ball
  CHECK_FALSE(touches(*h, small_tet_at(2.0, 0.5, 0.5), 3));  // outside the ball
}

TEST_CASE(
    "hemisphere: a cell crossing the sphere only on the excluded side of the rim is not selected",
    "[region][3d]") {
  // A straddles nothing; B is inside the ball at x < 1/2; only D is at x > 1/2
  // and the part of the tet with x >= 1/2 stays more than 1.03 from the centre.
  const std::vector<double> tet = {0.4, 1.6, 0.5, 0.4, 1.3, 0.5, 0.45, 1.3, 0.6, 0.6, 2.0, 0.5};
  CHECK_FALSE(touches(*spec(kPaperHemisphere, 3), tet, 3));
  // The full sphere does cross it.
  CHECK(touches(*spec(R"({"type":"sphere","center":[0.5,0.5,0.5],"radius":1})", 3), tet, 3));
}

// Never misses: samples in the kept halfspace on both sides of the sphere
// mean touches() is true. If touches() is true, samples come within a
// lattice spacing of the halfspace and of the sphere.
static void check_hemisphere_against_sampling(int dim) {
  std::mt19937_64 rng(777 + dim);
  std::uniform_real_distribution<double> radius(0.1, 0.9), gauss_free(-1, 1);
  const int n = dim == 4 ? 10 : 16;
  Tally tally;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::vector<double> c = random_point(rng, dim, 0, 1);
    const double r = std::stod(std::to_string(radius(rng)));
    std::vector<double> nrm = random_point(rng, dim, -1, 1);
    double len = 0;
    for (double x : nrm)
      len += x * x;
    len = std::sqrt(len);
    for (double &x : nrm)
      x = std::stod(std::to_string(x / len));
    const double off = std::stod(std::to_string(gauss_free(rng) * 0.5));
    double cn = 0;
    for (int k = 0; k < dim; ++k)
      cn += c[k] * nrm[k];
    auto region = spec(R"({"type":"hemisphere","center":)" + vec_json(c) + R"(,"radius":)" +
                           std::to_string(r) + R"(,"normal":)" + vec_json(nrm) + R"(,"offset":)" +
                           std::to_string(cn + off * r) + "}",
                       dim);
    const double offset = std::stod(std::to_string(cn + off * r));
    const std::vector<double> verts = random_simplex(rng, dim);
    const std::vector<double> pts = lattice(verts, dim, n);
    double dmin = 1e300, dmax = 0, smax = -1e300, dmin_all = 1e300;
    for (std::size_t p = 0; p < pts.size(); p += dim) {
      double s = -offset;
      for (int k = 0; k < dim; ++k)
        s += pts[p + k] * nrm[k];
      const double d = norm_to(&pts[p], c);
      smax = std::max(smax, s);
      dmin_all = std::min(dmin_all, d);
      if (s < 0)
        continue;
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
    }
    const bool sampled = dmin <= r && r <= dmax;
    const bool got = touches(*region, verts, dim);
    INFO("trial " << trial);
    if (sampled)
      CHECK(got);
    if (got) {
      const double h = lattice_spacing(verts, dim, n);
      CHECK(smax >= -h);
      CHECK(dmin_all <= r + h);
    }
    tally.sampled_hits += sampled;
    (got ? tally.selected : tally.rejected)++;
  }
  CHECK(tally.sampled_hits > 100);
  CHECK(tally.rejected > 100);
}

TEST_CASE("hemisphere: never misses a cell that dense sampling shows crossing it (2D)",
          "[region][2d]") {
  check_hemisphere_against_sampling(2);
}
TEST_CASE("hemisphere: never misses a cell that dense sampling shows crossing it (3D)",
          "[region][3d]") {
  check_hemisphere_against_sampling(3);
}
TEST_CASE("hemisphere: never misses a cell that dense sampling shows crossing it (4D)",
          "[region][4d]") {
  check_hemisphere_against_sampling(4);
}

// ---------------------------------------------------------------------------
// box

TEST_CASE("box: a triangle cutting a corner touches; one in the bounding-box overlap but past the "
          "corner does not",
          "[region][2d]") {
  auto box = spec(R"({"type":"box","min":[0,0],"max":[1,1]})", 2);
  CHECK(touches(*box, {1.2, 0.5, 0.5, 1.2, 1.5, 1.5}, 2));       // edge x+y = 1.7 cuts the corner
  CHECK_FALSE(touches(*box, {1.2, 0.9, 0.9, 1.2, 1.5, 1.5}, 2)); // edge x+y = 2.1 passes it
  CHECK(touches(*box, {0.2, 0.2, 0.3, 0.2, 0.2, 0.3}, 2));       // inside
  CHECK(touches(*box, {-1, -1, 3, -1, -1, 3}, 2));               // holds the whole box
  CHECK(touches(*box, {1, 1, 2, 1, 1, 2}, 2));                   // a vertex on the corner
}

TEST_CASE("box: exact where facet-normal separation is not enough (edge passing a box edge)",
          "[region][3d]") {
  auto box = spec(R"({"type":"box","min":[0,0,0],"max":[1,1,1]})", 3);
  // A needle-like tet: its edge AB runs along x+y = 2.1, just past the box
  // edge x = y = 1; only the plane x+y = 2.05 separates (edge x edge axis).
  const std::vector<double> past = {1.6, 0.5, 0.5, 0.5, 1.6, 0.5, 1.6, 1.6, 0.0, 1.6, 1.6, 1.0};
  CHECK_FALSE(touches(*box, past, 3));
  const std::vector<double> cutting = {1.4, 0.5, 0.5, 0.5, 1.4, 0.5, 1.6, 1.6, 0.0, 1.6, 1.6, 1.0};
  CHECK(touches(*box, cutting, 3));
}

TEST_CASE("box: a flat (plane) box is handled", "[region][3d]") {
  auto plane = spec(R"({"type":"box","min":[0,0,0.5],"max":[1,1,0.5]})", 3);
  CHECK(touches(*plane, small_tet_at(0.5, 0.5, 0.5), 3));
  CHECK_FALSE(touches(*plane, small_tet_at(0.5, 0.5, 0.6), 3));
}

// Never misses a sample in the box; exact: if touches(), a sample lies within
// a lattice spacing of the box.
static void check_box_against_sampling(int dim) {
  std::mt19937_64 rng(4242 + dim);
  std::uniform_real_distribution<double> size(0.1, 1.0);
  const int n = dim == 4 ? 10 : 16;
  Tally tally;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<double> lo = random_point(rng, dim, -0.2, 0.8), hi(dim);
    for (int k = 0; k < dim; ++k) {
      lo[k] = std::stod(std::to_string(lo[k]));
      hi[k] = std::stod(std::to_string(lo[k] + size(rng)));
    }
    auto region =
        spec(R"({"type":"box","min":)" + vec_json(lo) + R"(,"max":)" + vec_json(hi) + "}", dim);
    const std::vector<double> verts = random_simplex(rng, dim);
    const std::vector<double> pts = lattice(verts, dim, n);
    double dmin = 1e300;
    for (std::size_t p = 0; p < pts.size(); p += dim) {
      double s = 0;
      for (int k = 0; k < dim; ++k) {
        const double x = pts[p + k], d = x < lo[k] ? lo[k] - x : (x > hi[k] ? x - hi[k] : 0);
        s += d * d;
      }
      dmin = std::min(dmin, std::sqrt(s));
    }
    const bool got = touches(*region, verts, dim);
    INFO("trial " << trial);
    if (dmin == 0)
      CHECK(got);
    if (got)
      CHECK(dmin <= lattice_spacing(verts, dim, n));
    tally.sampled_hits += dmin == 0;
    (got ? tally.selected : tally.rejected)++;
  }
  CHECK(tally.selected > 100);
  CHECK(tally.rejected > 100);
}

TEST_CASE("box: touches exactly the simplices that meet it (dense sampling) (2D)", "[region][2d]") {
  check_box_against_sampling(2);
}
TEST_CASE("box: touches exactly the simplices that meet it (dense sampling) (3D)", "[region][3d]") {
  check_box_against_sampling(3);
}
TEST_CASE("box: touches exactly the simplices that meet it (dense sampling) (4D)", "[region][4d]") {
  check_box_against_sampling(4);
}

// ---------------------------------------------------------------------------
// halfspace, union, intersection

TEST_CASE("halfspace: a cell touches iff one of its vertices is in it", "[region][2d][3d]") {
  auto h2 = spec(R"({"type":"halfspace","normal":[1,1],"offset":1})", 2);
  CHECK(touches(*h2, {0, 0, 0.5, 0.5, 0, 0.4}, 2)); // vertex on the plane
  CHECK_FALSE(touches(*h2, {0, 0, 0.49, 0.5, 0, 0.4}, 2));
  auto h3 = spec(R"({"type":"halfspace","normal":[0,0,-2],"offset":-1})", 3); // z <= 1/2
  CHECK(touches(*h3, small_tet_at(0, 0, 0.52), 3));
  CHECK_FALSE(touches(*h3, small_tet_at(0, 0, 0.6), 3));
}

TEST_CASE("union touches where any member does; intersection needs every member", "[region][3d]") {
  auto u = spec(R"({"type":"union","regions":[
      {"type":"sphere","center":[-1,0,0],"radius":0.5},
      {"type":"sphere","center":[1,0,0],"radius":0.5}]})",
                3);
  CHECK(touches(*u, small_tet_at(-1.5, 0, 0), 3));
  CHECK(touches(*u, small_tet_at(1.5, 0, 0), 3));
  CHECK_FALSE(touches(*u, small_tet_at(0, 0, 0), 3));
  auto i = spec(R"({"type":"intersection","regions":[
      {"type":"box","min":[-0.5,-0.5,-0.5],"max":[0.5,0.5,0.5]},
      {"type":"halfspace","normal":[1,1,1],"offset":0}]})",
                3);
  CHECK(touches(*i, small_tet_at(0.3, 0.3, 0.3), 3));
  CHECK_FALSE(touches(*i, small_tet_at(-0.3, -0.3, -0.3), 3)); // in the box, wrong side
  CHECK_FALSE(touches(*i, small_tet_at(0.9, 0.9, 0.9), 3));    // right side, outside the box
}

// ---------------------------------------------------------------------------
// moving_sphere

TEST_CASE("moving_sphere: a cell touches at the time the sphere passes, not later",
          "[region][4d]") {
  // Seed 000 Section 5.3: radius 1/5, centre (0,0,t) at time t.
  auto m = spec(R"({"type":"moving_sphere","center":[0,0,0],"velocity":[0,0,1],"radius":0.2})", 4);
  auto cell_at = [](double x, double y, double z, double t) {
    const double h = 0.02;
    return std::vector<double>{x, y, z, t, x + h, y, z, t, x, y + h,
                               z, t, x, y, z + h, t, x, y, z, t + h};
  };
  CHECK(touches(*m, cell_at(0.19, 0, 0.5, 0.5), 4));       // on the sphere at t = 1/2
  CHECK_FALSE(touches(*m, cell_at(0.19, 0, 0.5, 0.9), 4)); // the sphere has moved on
  CHECK_FALSE(touches(*m, cell_at(0.0, 0, 0.5, 0.5), 4));  // inside the moving ball
  auto solid = spec(
      R"({"type":"moving_sphere","center":[0,0,0],"velocity":[0,0,1],"radius":0.2,"solid":true})",
      4);
  CHECK(touches(*solid, cell_at(0.0, 0, 0.5, 0.5), 4));
  CHECK_FALSE(touches(*solid, cell_at(0.0, 0, 0.5, 0.9), 4));
}

TEST_CASE("moving_sphere: a circle moving in the plane over time (2D+t)", "[region][3d]") {
  auto m = spec(R"({"type":"moving_sphere","center":[0,0],"velocity":[1,0],"radius":0.25})", 3);
  // A long thin cell along t at x = 0.75, y = 0: the circle reaches it at
  // t in [0.5, 1]; its vertices (t = 0 and t = 2) are all away from it.
  const std::vector<double> cell = {0.75, 0, 0, 0.76, 0, 0, 0.75, 0.01, 0, 0.75, 0, 2};
  CHECK(touches(*m, cell, 3));
  CHECK_FALSE(touches(
      *spec(R"({"type":"moving_sphere","center":[0,0.5],"velocity":[1,0],"radius":0.25})", 3), cell,
      3));
}

// f(x,t) = |x - c0 - v t| is Lipschitz with constant sqrt(1 + |v|^2).
static void check_moving_sphere_against_sampling(int dim, bool solid) {
  std::mt19937_64 rng(99 + dim + (solid ? 7 : 0));
  std::uniform_real_distribution<double> radius(0.05, 0.6);
  const int n = dim == 4 ? 10 : 16;
  Tally tally;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<double> c = random_point(rng, dim - 1, -0.2, 1.2),
                        v = random_point(rng, dim - 1, -1, 1);
    for (double &x : c)
      x = std::stod(std::to_string(x));
    for (double &x : v)
      x = std::stod(std::to_string(x));
    const double r = std::stod(std::to_string(radius(rng)));
    auto region = spec(R"({"type":"moving_sphere","center":)" + vec_json(c) + R"(,"velocity":)" +
                           vec_json(v) + R"(,"radius":)" + std::to_string(r) +
                           (solid ? R"(,"solid":true})" : "}"),
                       dim);
    const std::vector<double> verts = random_simplex(rng, dim);
    const std::vector<double> pts = lattice(verts, dim, n);
    double dmin = 1e300, dmax = 0, v2 = 0;
    for (double x : v)
      v2 += x * x;
    for (std::size_t p = 0; p < pts.size(); p += dim) {
      double s = 0;
      for (int k = 0; k < dim - 1; ++k)
        s += std::pow(pts[p + k] - c[k] - v[k] * pts[p + dim - 1], 2);
      dmin = std::min(dmin, std::sqrt(s));
      dmax = std::max(dmax, std::sqrt(s));
    }
    const bool sampled = solid ? dmin <= r : dmin <= r && r <= dmax;
    const bool got = touches(*region, verts, dim);
    INFO("trial " << trial);
    if (sampled)
      CHECK(got);
    if (got) {
      CHECK(dmin <= r + lattice_spacing(verts, dim, n) * std::sqrt(1 + v2));
      if (!solid)
        CHECK(dmax >= r);
    }
    (got ? tally.selected : tally.rejected)++;
  }
  CHECK(tally.selected > 100);
  CHECK(tally.rejected > 100);
}

TEST_CASE("moving_sphere: never misses a cell dense sampling shows crossing it, and is exact (3D)",
          "[region][3d]") {
  check_moving_sphere_against_sampling(3, false);
  check_moving_sphere_against_sampling(3, true);
}
TEST_CASE("moving_sphere: never misses a cell dense sampling shows crossing it, and is exact (4D)",
          "[region][4d]") {
  check_moving_sphere_against_sampling(4, false);
  check_moving_sphere_against_sampling(4, true);
}

// ---------------------------------------------------------------------------
// bounds

TEST_CASE("bounds: every point of the region lies inside them", "[region][2d][3d][4d]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  for (int dim = 2; dim <= 4; ++dim) {
    INFO("dim " << dim);
    std::vector<double> c(dim, 0.5), n(dim, 0.0), zero(dim, 0.0);
    n[0] = -1; // hemisphere x_0 <= 0.3
    const std::string cs = vec_json(c), ns = vec_json(n);
    auto sphere = spec(R"({"type":"sphere","center":)" + cs + R"(,"radius":0.25})", dim);
    auto hemi = spec(R"({"type":"hemisphere","center":)" + cs + R"(,"radius":0.25,"normal":)" + ns +
                         R"(,"offset":-0.3})",
                     dim);
    double lo[4], hi[4], hlo[4], hhi[4];
    sphere->bounds(lo, hi, dim);
    hemi->bounds(hlo, hhi, dim);
    CHECK(hhi[0] == Approx(0.3)); // cut by the plane
    CHECK(hlo[0] == Approx(0.25));
    for (int s = 0; s < 200; ++s) {
      std::vector<double> x(dim);
      double len = 0;
      for (double &a : x) {
        a = g(rng);
        len += a * a;
      }
      for (int k = 0; k < dim; ++k)
        x[k] = c[k] + 0.25 * x[k] / std::sqrt(len);
      for (int k = 0; k < dim; ++k) {
        CHECK(x[k] >= lo[k] - 1e-12);
        CHECK(x[k] <= hi[k] + 1e-12);
        if (x[0] <= 0.3) {
          CHECK(x[k] >= hlo[k] - 1e-12);
          CHECK(x[k] <= hhi[k] + 1e-12);
        }
      }
    }
    auto half = spec(R"({"type":"halfspace","normal":[1,1)" + std::string(dim > 2 ? ",1" : "") +
                         (dim > 3 ? ",0" : "") + R"(],"offset":0})",
                     dim);
    half->bounds(lo, hi, dim);
    for (int k = 0; k < dim; ++k)
      CHECK((std::isinf(lo[k]) && std::isinf(hi[k])));
  }
  auto moving =
      spec(R"({"type":"moving_sphere","center":[0,0,0],"velocity":[0,0,1],"radius":0.2})", 4);
  double lo[4], hi[4];
  moving->bounds(lo, hi, 4);
  CHECK(lo[0] == Approx(-0.2));
  CHECK(hi[1] == Approx(0.2));
  CHECK(std::isinf(lo[2]));
  CHECK(std::isinf(hi[3]));
  auto u = spec(R"({"type":"union","regions":[{"type":"box","min":[0,0],"max":[1,1]},
                                              {"type":"box","min":[2,-1],"max":[3,0.5]}]})",
                2);
  u->bounds(lo, hi, 2);
  CHECK((lo[0] == 0 && lo[1] == -1 && hi[0] == 3 && hi[1] == 1));
}

// ---------------------------------------------------------------------------
// spec errors

static std::string error_of(const std::string &text, int dim) {
  try {
    spec(text, dim);
  } catch (const InputError &e) {
    return e.what();
  }
  return "(no error)";
}

TEST_CASE("spec errors name the file and the field", "[region][io]") {
  CHECK(error_of(R"({"type":"cube"})", 3) == "test.json: unknown region type \"cube\" (expected "
                                             "sphere, hemisphere, box, halfspace, moving_sphere, "
                                             "levelset, union, intersection)");
  CHECK(error_of(R"({"type":"sphere","center":[0,0],"radius":1})", 3) ==
        "test.json: sphere: \"center\" has 2 entries, the mesh is 3D");
  CHECK(error_of(R"({"type":"sphere","center":[0,0],"radius":-1})", 2) ==
        "test.json: sphere: \"radius\" must be a positive number");
  CHECK(error_of(R"({"type":"sphere","center":[0,0],"radius":"1"})", 2) ==
        "test.json: sphere: \"radius\" must be a positive number");
  CHECK(error_of(R"({"type":"sphere","center":[0,0]})", 2) ==
        "test.json: sphere: missing \"radius\"");
  CHECK(error_of(R"({"type":"sphere","center":[0,0],"radius":1,"radios":2})", 2) ==
        "test.json: sphere: unknown field \"radios\" (expected center, radius, solid, name, "
        "comment)");
  CHECK(error_of(R"({"type":"sphere","center":[0,0],"radius":1,"solid":"yes"})", 2) ==
        "test.json: sphere: \"solid\" must be true or false");
  CHECK(error_of(R"({"type":"sphere","center":[0,1e999],"radius":1})", 2) ==
        "test.json: invalid JSON: number overflow parsing '1e999'");
  CHECK(error_of(R"({"type":"sphere","center":[0,null],"radius":1})", 2) ==
        "test.json: sphere: \"center\" entry 1 must be a finite number");
  CHECK(error_of(R"({"center":[0,0],"radius":1})", 2).rfind("test.json: missing \"type\"", 0) == 0);
  CHECK(error_of(R"({"type":"halfspace","normal":[0,0],"offset":1})", 2) ==
        "test.json: halfspace: \"normal\" must not be zero");
  CHECK(error_of(R"({"type":"halfspace","normal":[1,0]})", 2) ==
        "test.json: halfspace: missing \"offset\"");
  CHECK(error_of(R"({"type":"hemisphere","center":[0,0],"radius":1,"normal":[1,0],"offset":true})",
                 2) == "test.json: hemisphere: \"offset\" must be a finite number");
  CHECK(error_of(R"({"type":"box","min":[0,2],"max":[1,1]})", 2) ==
        "test.json: box: \"min\" exceeds \"max\" in coordinate 1 (2.0 > 1.0)");
  CHECK(error_of(R"({"type":"union","regions":[]})", 2) ==
        "test.json: union: \"regions\" must be a non-empty array of regions");
  CHECK(error_of(R"({"type":"union","regions":[{"type":"sphere","center":[0,0],"radius":1},
                                               {"type":"box","min":[0,0],"max":[1]}]})",
                 2) == "test.json: regions[1]: box: \"max\" has 1 entry, the mesh is 2D");
  CHECK(error_of(R"({"type":"union","regions":[{"type":"intersection","regions":[3]}]})", 2) ==
        "test.json: regions[0].regions[0]: a region must be a JSON object with a \"type\" field");
  CHECK(error_of(R"({"type":"moving_sphere","center":[0],"velocity":[1],"radius":1})", 2) ==
        "test.json: moving_sphere: needs a space-time mesh (3D or 4D, time last); the mesh is 2D");
  CHECK(error_of(R"({"type":"moving_sphere","center":[0,0,0],"velocity":[1,0],"radius":1})", 3) ==
        "test.json: moving_sphere: \"center\" has 3 entries, expected 2 (the space dimensions of a "
        "3D "
        "space-time mesh)");
  CHECK(error_of("[1, 2]", 2) ==
        "test.json: the region spec must be a JSON object with a \"type\" field, not array");
  CHECK(error_of("  \n", 2) ==
        "test.json: empty region spec (expected a JSON object with a \"type\" field)");
  // "name" and "comment" are allowed everywhere.
  CHECK_NOTHROW(spec(R"({"type":"box","name":"b","comment":"c","min":[0,0],"max":[1,1]})", 2));
}

TEST_CASE("spec errors: JSON syntax errors give the line and column", "[region][io]") {
  const std::string text = "{\n  \"type\": \"sphere\",\n  \"radius\": 1,,\n}";
  const std::string e = error_of(text, 3);
  INFO(e);
  CHECK(e.rfind("test.json: line 3, column 15: invalid JSON: ", 0) == 0);
  CHECK(e.find('\n') == std::string::npos);
  CHECK(error_of("{\"type\": \"sphere\"", 3).rfind("test.json: line 1, column ", 0) == 0);
}

TEST_CASE("read_region: a missing file or a directory is named in the error", "[region][io]") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "bisect_test_region";
  fs::create_directories(dir);
  const std::string missing = (dir / "nope.json").string();
  CHECK_THROWS_WITH(read_region(missing, 3), Catch::Matchers::StartsWith(missing + ": "));
  CHECK_THROWS_WITH(read_region(dir.string(), 3), dir.string() + ": is a directory");
  const std::string bad = (dir / "bad.json").string();
  std::ofstream(bad) << R"({"type": "cube"})";
  CHECK_THROWS_WITH(read_region(bad, 3),
                    Catch::Matchers::StartsWith(bad + ": unknown region type \"cube\""));
  fs::remove_all(dir);
}

TEST_CASE("read_region: the bundled example specs parse for their mesh dimension", "[region][io]") {
  const std::string dir = std::string(BISECT_DATA_DIR) + "/regions/";
  const std::vector<std::pair<std::string, int>> files = {
      {"ball-solid.json", 3}, {"box2d.json", 2},       {"circle.json", 2},
      {"hemisphere.json", 3}, {"hypersphere.json", 4}, {"moving-sphere.json", 4},
      {"sphere.json", 3},     {"union.json", 3}};
  for (const auto &[name, dim] : files) {
    INFO(name);
    CHECK(read_region(dir + name, dim) != nullptr);
  }
  CHECK_THROWS_AS(read_region(dir + "circle.json", 3), InputError); // wrong dimension
}

TEST_CASE("sphere: a sphere far smaller than a cell selects the cell holding its centre, "
          "whatever the radius and the coordinates' magnitude",
          "[region][2d][3d][4d]") {
  for (int dim : {2, 3, 4})
    for (double offset : {0.0, 1e6, -3e9}) {
      // One simplex of size ~1 at the offset, the centre at its centroid.
      std::vector<double> verts(std::size_t((dim + 1) * dim), offset);
      for (int i = 1; i <= dim; ++i)
        verts[std::size_t(i * dim + i - 1)] += 1.0;
      verts[std::size_t(dim)] += 0.25; // not a right-angled corner
      std::vector<double> c(std::size_t(dim), 0.0);
      for (int i = 0; i <= dim; ++i)
        for (int k = 0; k < dim; ++k)
          c[std::size_t(k)] += verts[std::size_t(i * dim + k)] / (dim + 1);
      for (double r : {1e-3, 1e-9, 1e-15, 1e-100, 1e-300})
        for (bool solid : {false, true}) {
          std::string spec = R"({"type": "sphere", "center": [)";
          for (int k = 0; k < dim; ++k) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", c[std::size_t(k)]);
            spec += buf;
          }
          char rb[64];
          std::snprintf(rb, sizeof rb, "%.17g", r);
          spec += std::string("], \"radius\": ") + rb + (solid ? R"(, "solid": true})" : "}");
          INFO(dim << "D, offset " << offset << ", radius " << r << (solid ? ", solid" : ""));
          auto region = parse_region(spec, dim, "test");
          CHECK(region->touches(verts.data(), dim));
          // A cell beside it (the simplex moved by 2 along x) is not selected.
          std::vector<double> far = verts;
          for (int i = 0; i <= dim; ++i)
            far[std::size_t(i * dim)] += 2.0;
          CHECK_FALSE(region->touches(far.data(), dim));
        }
    }
}

TEST_CASE("select_touching keeps exactly the cells whose simplex touches the region, in order",
          "[region][2d][3d][4d]") {
  // The selection reads cells in batches of 16; a cell count that is not a
  // multiple of it, with and without candidates (every third cell), against
  // touches() asked cell by cell.
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = generate_kuhn(dim, dim == 2 ? 7 : 3); // 98, 162, 1944 cells
  const std::string centre = dim == 2   ? "[0.5, 0.5]"
                             : dim == 3 ? "[0.5, 0.5, 0.5]"
                                        : "[0.5, 0.5, 0.5, 0.5]";
  const auto region =
      spec(R"({"type": "sphere", "center": )" + centre + R"(, "radius": 0.3})", dim);
  std::vector<std::uint64_t> candidates((m.num_cells() + 63) / 64, 0);
  for (std::size_t c = 0; c < m.num_cells(); c += 3)
    candidates[c / 64] |= std::uint64_t(1) << (c % 64);
  std::vector<CellId> all, among;
  std::vector<double> p((dim + 1) * dim);
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    cell_points(m, CellId(c), p.data());
    if (region->touches(p.data(), dim)) {
      all.push_back(CellId(c));
      if (c % 3 == 0)
        among.push_back(CellId(c));
    }
  }
  INFO("dim " << dim << ", " << m.num_cells() << " cells, " << all.size() << " touch");
  REQUIRE(m.num_cells() % 16 != 0);
  REQUIRE(all.size() > 16);
  REQUIRE(all.size() < m.num_cells());
  CHECK(select_touching(m, *region) == all);
  CHECK(select_touching(m, *region, &candidates) == among);
}
