// Sections of 4D meshes by hyperplanes x[axis] = value (slice.hpp).
#include "bisect/slice.hpp"

#include "bisect/check.hpp"
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

using namespace bisect;

namespace {

// The slice is a valid conforming 3D mesh: check_conformity passes and
// prepare_input accepts it (no degenerate tet, no hanging node).
void require_valid_slice(const Mesh &s) {
  REQUIRE(s.dim == 3);
  REQUIRE_FALSE(s.marked());
  const CheckResult r = check_conformity(s);
  INFO(r.failure);
  REQUIRE(r.ok);
  Mesh copy = s;
  REQUIRE_NOTHROW(prepare_input(copy, "slice"));
  // Every tet is positively oriented and every vertex is used.
  std::vector<bool> used(s.num_vertices(), false);
  for (std::size_t c = 0; c < s.num_cells(); ++c) {
    double pts[12];
    cell_points(s, CellId(c), pts);
    REQUIRE(signed_volume(pts, 3) > 0);
    for (int i = 0; i < 4; ++i)
      used[s.cell(CellId(c))[i]] = true;
  }
  REQUIRE(std::count(used.begin(), used.end(), false) == 0);
}

// The section of [0,1]^4 by any axis hyperplane inside it is the unit cube.
void require_unit_cube_section(const Mesh &s) {
  require_valid_slice(s);
  const Invariants inv = measure_invariants(s);
  REQUIRE(inv.volume == Approx(1.0).epsilon(1e-12));
  REQUIRE(inv.boundary_measure == Approx(6.0).epsilon(1e-12));
  REQUIRE(inv.euler == 1);
}

} // namespace

TEST_CASE("slice: sections of Kuhn hypercubes are conforming unit cubes on every axis",
          "[slice][4d]") {
  for (int k : {1, 2, 3}) {
    const Mesh m = generate_kuhn(4, k);
    for (int axis = 0; axis < 4; ++axis) {
      // 0.5 passes through vertices when k = 2; 0 and 1 contain boundary facets.
      for (double value : {0.5, 0.37, 0.0, 1.0, 1.0 / 3.0, 0.9}) {
        INFO("k " << k << " axis " << axis << " value " << value);
        require_unit_cube_section(slice_mesh(m, axis, value));
      }
    }
  }
}

TEST_CASE("slice: a hyperplane a rounding error or 1e-7 from a layer of vertices cuts through it",
          "[slice][4d]") {
  // Cut points a hair apart on one vertex's edges made degenerate tets (the
  // fuzzer: a Kuhn hypercube at t = 1e-7; the sample cylinder at t = 0.5
  // with vertices at 0.49999999999999872). Within 1e-6 of the axis extent of
  // a vertex's cells, the vertex counts as on the plane: the section is the
  // one through the layer.
  for (int k : {1, 2}) {
    const Mesh m = generate_kuhn(4, k);
    for (int axis = 0; axis < 4; ++axis)
      for (double layer : {0.0, k == 2 ? 0.5 : 1.0})
        for (double offset : {1e-7, -1e-7, 1e-15, -4e-16, 1e-12}) {
          const double value = layer + offset;
          if (value < 0 || value > 1)
            continue;
          INFO("k " << k << " axis " << axis << " value " << value);
          const Mesh s = slice_mesh(m, axis, value);
          require_unit_cube_section(s);
          const Mesh at_layer = slice_mesh(m, axis, layer);
          REQUIRE(s.cells == at_layer.cells);
          REQUIRE(s.coords == at_layer.coords);
        }
  }
  // Further off, the cut is where it was asked.
  const Mesh s = slice_mesh(generate_kuhn(4, 1), 3, 1e-4);
  require_unit_cube_section(s);
  REQUIRE(s.cells != slice_mesh(generate_kuhn(4, 1), 3, 0.0).cells);
}

TEST_CASE("slice: a hyperplane through interior facets produces each in-plane tet once",
          "[slice][4d]") {
  // At t = 0.5 with k = 2 whole tetrahedral facets lie in the plane; the
  // slice has as many cells as the 3D Kuhn mesh of the same grid (2^3 * 6).
  const Mesh s = slice_mesh(generate_kuhn(4, 2), 3, 0.5);
  require_unit_cube_section(s);
  REQUIRE(s.num_cells() == 48);
  REQUIRE(s.num_vertices() == 27);
}

TEST_CASE("slice: sections of a perturbed Kuhn mesh are conforming unit cubes", "[slice][4d]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Mesh m = testing::perturbed_inside_box(generate_kuhn(4, 3), 0.08, seed);
    for (int axis = 0; axis < 4; ++axis)
      for (double value : {0.21, 0.5, 0.77}) {
        INFO("seed " << seed << " axis " << axis << " value " << value);
        require_unit_cube_section(slice_mesh(m, axis, value));
      }
  }
}

TEST_CASE("slice: sections of a locally refined 4D mesh are conforming unit cubes", "[slice][4d]") {
  for (Marking mk : {Marking::Longest, Marking::Index}) {
    Mesh m = generate_kuhn(4, 2);
    mark_mesh(m, mk);
    auto region =
        parse_region(R"({"type":"sphere","center":[0.5,0.5,0.5,0.5],"radius":0.3})", 4, "t");
    for (int it = 0; it < 4; ++it)
      refine(m, select_cells(m, *region));
    REQUIRE(m.num_cells() > 384);
    // t = 0.25 meets every side pattern, the square pyramid (2,1,2) included.
    // A volume and boundary measure of the unit cube also catch quads cut by
    // different diagonals on the two sides (check_conformity alone does not).
    for (double t : {0.0, 0.2, 0.25, 0.375, 0.41, 0.5, 0.5625, 0.7, 1.0}) {
      INFO("marking " << marking_name(mk) << " t " << t);
      require_unit_cube_section(slice_mesh(m, 3, t));
    }
    for (int axis = 0; axis < 3; ++axis)
      require_unit_cube_section(slice_mesh(m, axis, 0.45));
  }
}

TEST_CASE("slice: the vertex order inside each pentatope does not matter", "[slice][4d]") {
  const Mesh m = generate_kuhn(4, 2);
  Mesh shuffled = m;
  std::mt19937_64 rng(42);
  for (std::size_t c = 0; c < shuffled.num_cells(); ++c)
    std::shuffle(shuffled.cell(CellId(c)), shuffled.cell(CellId(c)) + 5, rng);
  for (double t : {0.5, 0.37, 0.0, 1.0}) {
    const Mesh a = slice_mesh(m, 3, t), b = slice_mesh(shuffled, 3, t);
    require_unit_cube_section(b);
    REQUIRE(a.num_cells() == b.num_cells());
    REQUIRE(a.num_vertices() == b.num_vertices());
  }
}

TEST_CASE("slice: linear point data is reproduced exactly at the cut points", "[slice][4d]") {
  Mesh m = testing::perturbed_inside_box(generate_kuhn(4, 2), 0.1, 5);
  auto f = [](const double *x) { return 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2] + 4.0 * x[3]; };
  DataArray lin{"f", 2, {}};
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    lin.values.push_back(f(m.point(VertexId(v))));
    lin.values.push_back(-f(m.point(VertexId(v))));
  }
  m.point_data.push_back(lin);
  m.cell_data.push_back({"id", 1, {}});
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    m.cell_data[0].values.push_back(double(c));

  for (int axis = 0; axis < 4; ++axis)
    for (double value : {0.3, 0.5}) {
      const Mesh s = slice_mesh(m, axis, value);
      REQUIRE(s.point_data.size() == 1);
      REQUIRE(s.point_data[0].name == "f");
      REQUIRE(s.point_data[0].values.size() == 2 * s.num_vertices());
      for (std::size_t v = 0; v < s.num_vertices(); ++v) {
        double x[4];
        for (int d = 0, j = 0; d < 4; ++d)
          x[d] = d == axis ? value : s.point(VertexId(v))[j++];
        REQUIRE(s.point_data[0].values[2 * v] == Approx(f(x)).margin(1e-12));
        REQUIRE(s.point_data[0].values[2 * v + 1] == Approx(-f(x)).margin(1e-12));
      }
      // Cell data comes from the parent pentatope, whose x-range contains the value.
      REQUIRE(s.cell_data.size() == 1);
      REQUIRE(s.cell_data[0].values.size() == s.num_cells());
      for (std::size_t c = 0; c < s.num_cells(); ++c) {
        const CellId parent = CellId(s.cell_data[0].values[c]);
        double lo = 1e300, hi = -1e300;
        for (int i = 0; i < 5; ++i) {
          lo = std::min(lo, m.point(m.cell(parent)[i])[axis]);
          hi = std::max(hi, m.point(m.cell(parent)[i])[axis]);
        }
        REQUIRE(lo <= value);
        REQUIRE(value <= hi);
      }
    }
}

TEST_CASE("slice: bisection state arrays are not copied to the slice", "[slice][4d]") {
  Mesh m = generate_kuhn(4, 1);
  mark_mesh(m, Marking::Index);
  encode_state(m);
  const Mesh s = slice_mesh(m, 3, 0.5);
  for (const DataArray &a : s.cell_data)
    REQUIRE(a.name.rfind("bisect:", 0) != 0);
}

TEST_CASE("slice: a hyperplane missing the mesh gives an empty 3D mesh", "[slice][4d]") {
  const Mesh m = generate_kuhn(4, 2);
  for (double value : {-0.5, 1.5}) {
    const Mesh s = slice_mesh(m, 3, value);
    REQUIRE(s.dim == 3);
    REQUIRE(s.num_cells() == 0);
    REQUIRE(s.num_vertices() == 0);
  }
}

TEST_CASE("slice: bad axis or a mesh that is not 3D or 4D is rejected", "[slice][4d]") {
  const Mesh m = generate_kuhn(4, 1);
  REQUIRE_THROWS_AS(slice_mesh(m, 4, 0.5), InputError);
  REQUIRE_THROWS_AS(slice_mesh(m, -1, 0.5), InputError);
  REQUIRE_THROWS_AS(slice_mesh(generate_kuhn(3, 1), 3, 0.5), InputError);
  REQUIRE_THROWS_AS(slice_mesh(generate_kuhn(2, 1), 1, 0.5), InputError);
}

TEST_CASE("slice: sections of locally refined 3D (2D+t) meshes are conforming unit squares",
          "[slice][3d]") {
  // Planes through the interior, through vertices of the initial mesh (in-plane
  // triangles must appear once) and through midpoints made by refinement.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    for (Marking mk : {Marking::Longest, Marking::Sorted}) {
      Mesh m =
          testing::renumbered(testing::perturbed_inside_box(generate_kuhn(3, 3), 0.05, seed), seed);
      prepare_input(m, "kuhn");
      mark_mesh(m, mk);
      auto region =
          parse_region(R"({"type":"sphere","center":[0.4,0.5,0.45],"radius":0.3})", 3, "r");
      for (int it = 0; it < 5; ++it)
        refine(m, select_cells(m, *region));
      for (int axis = 0; axis < 3; ++axis)
        for (double v : {0.0, 0.2, 0.5, 0.55, 1.0}) {
          Mesh s = slice_mesh(m, axis, v);
          INFO("seed " << seed << " axis " << axis << " value " << v);
          REQUIRE(s.dim == 2);
          const CheckResult r = check_conformity(s);
          INFO(r.failure);
          REQUIRE(r.ok);
          const Invariants inv = measure_invariants(s);
          REQUIRE(inv.volume == Approx(1.0).epsilon(1e-12));
          REQUIRE(inv.boundary_measure == Approx(4.0).epsilon(1e-12));
          REQUIRE(inv.euler == 1);
        }
    }
  }
}
