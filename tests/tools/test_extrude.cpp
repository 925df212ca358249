// Space-time extrusion of 3D meshes by 4D Delaunay (seed 000 §5.2).
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

using namespace bisect;

namespace {

// The Kuhn cube [0,1]^3 minus the cells whose centroid lies in [0.5,1]^3.
Mesh l_shaped() {
  Mesh full = generate_kuhn(3, 2);
  Mesh m = full;
  m.cells.clear();
  for (std::size_t c = 0; c < full.num_cells(); ++c) {
    double pts[12];
    cell_points(full, CellId(c), pts);
    bool corner = true;
    for (int k = 0; k < 3; ++k)
      corner = corner && (pts[k] + pts[3 + k] + pts[6 + k] + pts[9 + k]) / 4 > 0.5;
    if (!corner)
      m.cells.insert(m.cells.end(), full.cell(CellId(c)), full.cell(CellId(c)) + 4);
  }
  return m;
}

} // namespace

TEST_CASE("Extruding a Kuhn cube fills the unit hypercube conformingly", "[extrude][4d]") {
  Mesh m3 = generate_kuhn(3, 2);
  m3.point_data.push_back({"id", 1, {}});
  for (std::size_t v = 0; v < m3.num_vertices(); ++v)
    m3.point_data[0].values.push_back(double(v));
  Mesh m = extrude_delaunay(m3, {0, 0.5, 1});
  REQUIRE(m.dim == 4);
  REQUIRE(m.num_vertices() == 3 * m3.num_vertices());
  REQUIRE_FALSE(m.marked());
  for (std::size_t s = 0; s < 3; ++s)
    for (std::size_t v = 0; v < m3.num_vertices(); ++v) {
      const double *p = m.point(VertexId(s * m3.num_vertices() + v));
      for (int k = 0; k < 3; ++k)
        REQUIRE(p[k] == m3.point(VertexId(v))[k]);
      REQUIRE(p[3] == 0.5 * double(s));
      REQUIRE(m.point_data[0].values[s * m3.num_vertices() + v] == double(v));
    }
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    double pts[20];
    cell_points(m, CellId(c), pts);
    REQUIRE(signed_volume(pts, 4) > 0);
  }
  REQUIRE_NOTHROW(prepare_input(m, "extruded"));
  CheckResult r = check_conformity(m);
  INFO(r.failure);
  REQUIRE(r.ok);
  Invariants inv = measure_invariants(m);
  REQUIRE(inv.volume == Approx(1.0).epsilon(1e-12));
  REQUIRE(inv.euler == 1);
}

TEST_CASE("Extruding a perturbed convex mesh is conforming with the prism volume",
          "[extrude][4d]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Mesh m3 = testing::perturbed_inside_box(generate_kuhn(3, 3), 0.05, seed);
    Mesh m = extrude_delaunay(m3, {-0.5, 0.25, 0.5, 1.5});
    INFO("seed " << seed);
    REQUIRE_NOTHROW(prepare_input(m, "extruded"));
    CheckResult r = check_conformity(m);
    INFO(r.failure);
    REQUIRE(r.ok);
    Invariants inv = measure_invariants(m);
    REQUIRE(inv.volume == Approx(2.0).epsilon(1e-9));
    REQUIRE(inv.euler == 1);
  }
}

TEST_CASE("Extrusion rejects bad slices, a 2D mesh and a non-convex domain", "[extrude][4d]") {
  Mesh m3 = generate_kuhn(3, 1);
  REQUIRE_THROWS_AS(extrude_delaunay(m3, {}), InputError);
  REQUIRE_THROWS_AS(extrude_delaunay(m3, {0.0}), InputError);
  REQUIRE_THROWS_AS(extrude_delaunay(m3, {1.0, 0.0}), InputError);
  REQUIRE_THROWS_AS(extrude_delaunay(m3, {0.0, 0.0}), InputError);
  REQUIRE_THROWS_AS(extrude_delaunay(generate_kuhn(2, 1), {0.0, 1.0}), InputError);
  REQUIRE_THROWS_WITH(extrude_delaunay(l_shaped(), {0.0, 1.0}), Catch::Contains("not convex"));
  // A point array named t would be taken for the result's time coordinate.
  m3.point_data.push_back({"t", 1, std::vector<double>(m3.num_vertices(), 0.5)});
  REQUIRE_THROWS_WITH(extrude_delaunay(m3, {0.0, 1.0}), Catch::Contains("point array 't'"));
}

TEST_CASE("Local refinement of an extruded Kuhn cube stays conforming", "[extrude][4d]") {
  Mesh m = extrude_delaunay(generate_kuhn(3, 2), {0, 0.5, 1});
  prepare_input(m, "extruded");
  mark_mesh(m, Marking::Longest);
  Invariants inv = measure_invariants(m);
  auto region =
      parse_region(R"({"type":"sphere","center":[0.5,0.5,0.5,0.5],"radius":0.3})", 4, "t");
  for (int it = 1; it <= 4; ++it) {
    refine(m, select_cells(m, *region));
    INFO("iteration " << it);
    REQUIRE_CONFORMING(m, inv);
  }
}
