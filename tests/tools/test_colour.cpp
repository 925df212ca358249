// Vertex colourings: propagation, its proof of impossibility, barycentric
// subdivision (seed 001 §2-3).
#include "bisect/colour.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <iostream>

using namespace bisect;

namespace {

// `count` tetrahedra around the edge {0, 1} (0 below, 1 above the ring of
// vertices 2 .. count+1); closed ring: the edge is interior.
Mesh tets_around_edge(int count, bool closed = true) {
  Mesh m;
  m.dim = 3;
  m.coords = {0, 0, -1, 0, 0, 1};
  const int ring = closed ? count : count + 1;
  for (int i = 0; i < ring; ++i) {
    double a = (closed ? 2.0 : 1.5) * M_PI * i / (closed ? count : count);
    m.coords.insert(m.coords.end(), {std::cos(a), std::sin(a), 0.0});
  }
  for (int i = 0; i < count; ++i)
    m.cells.insert(m.cells.end(), {0, 1, VertexId(2 + i), VertexId(2 + (i + 1) % ring)});
  return m;
}

// `count` triangles around vertex 0.
Mesh triangles_around_vertex(int count) {
  Mesh m;
  m.dim = 2;
  m.coords = {0, 0};
  for (int i = 0; i < count; ++i)
    m.coords.insert(m.coords.end(),
                    {std::cos(2 * M_PI * i / count), std::sin(2 * M_PI * i / count)});
  for (int i = 0; i < count; ++i)
    m.cells.insert(m.cells.end(), {0, VertexId(1 + i), VertexId(1 + (i + 1) % count)});
  return m;
}

// A combinatorial mesh (no geometry needed by colour_mesh) of single cells.
Mesh cells_only(int dim, std::size_t nv, std::vector<VertexId> cells) {
  Mesh m;
  m.dim = dim;
  m.coords.assign(nv * dim, 0.0);
  m.cells = std::move(cells);
  return m;
}

double total_volume(const Mesh &m) {
  return measure_invariants(m).volume;
}

const DataArray &array_named(const std::vector<DataArray> &arrays, const std::string &name) {
  for (const DataArray &a : arrays)
    if (a.name == name)
      return a;
  FAIL("no array " << name);
  return arrays.front();
}

} // namespace

TEST_CASE("colouring: propagation colours renumbered Kuhn meshes", "[colour][2d][3d]") {
  for (int dim : {2, 3})
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      Mesh m = testing::renumbered(generate_kuhn(dim, 3), seed);
      Colouring c = colour_mesh(m);
      INFO("dim " << dim << " seed " << seed << ": " << c.why);
      REQUIRE(c.ok);
      REQUIRE(c.components == 1);
      REQUIRE(check_colouring(m, c.colour).empty());
      // Every colour is used, and the colouring is unique up to renaming: the
      // vertex of colour k in cell 0 has colour k in every cell it is in.
      std::vector<int> count(dim + 1, 0);
      for (std::uint8_t k : c.colour)
        count[k]++;
      for (int k = 0; k <= dim; ++k)
        REQUIRE(count[k] > 0);
    }
}

TEST_CASE("colouring: an interior edge in an odd number of tets proves there is none",
          "[colour][3d]") {
  for (int count : {3, 5, 7}) {
    Mesh m = tets_around_edge(count);
    Colouring c = colour_mesh(m);
    INFO(count << " tets: " << c.why);
    REQUIRE_FALSE(c.ok);
    REQUIRE_THAT(c.why, Catch::Contains("would need colours"));
    REQUIRE_THAT(c.why, Catch::Contains("interior edge 0-1 lies in " + std::to_string(count) +
                                        " tetrahedra"));
  }
  for (int count : {4, 6, 8}) { // even rings colour
    Mesh m = tets_around_edge(count);
    Colouring c = colour_mesh(m);
    INFO(count << " tets: " << c.why);
    REQUIRE(c.ok);
    REQUIRE(check_colouring(m, c.colour).empty());
  }
  // An odd number of tets around a boundary edge is no obstruction.
  Mesh open = tets_around_edge(3, false);
  REQUIRE(open.num_vertices() == 6);
  Colouring c = colour_mesh(open);
  REQUIRE(c.ok);
  REQUIRE(check_colouring(open, c.colour).empty());
}

TEST_CASE("colouring: an interior vertex in an odd number of triangles proves there is none",
          "[colour][2d]") {
  Colouring odd = colour_mesh(triangles_around_vertex(5));
  REQUIRE_FALSE(odd.ok);
  REQUIRE_THAT(odd.why, Catch::Contains("vertex 0 lies in 5 triangles"));
  Mesh even = triangles_around_vertex(6);
  Colouring c = colour_mesh(even);
  REQUIRE(c.ok);
  REQUIRE(check_colouring(even, c.colour).empty());
  // The bundled square has odd vertices: no 3-colouring.
  Mesh square = read_mesh(testing::data_path("square.msh"));
  prepare_input(square, "square");
  Colouring s = colour_mesh(square);
  REQUIRE_FALSE(s.ok);
  REQUIRE_THAT(s.why, Catch::Contains("odd number"));
}

TEST_CASE("colouring: a loop of cells is blamed when no interior vertex is odd", "[colour][2d]") {
  // A strip of 5 triangles closed into a ring (a Moebius strip): it has no
  // interior vertex at all, yet the forcing around the loop conflicts.
  Mesh m = cells_only(2, 5, {0, 1, 2, 1, 2, 3, 2, 3, 4, 3, 4, 0, 4, 0, 1});
  Colouring c = colour_mesh(m);
  REQUIRE_FALSE(c.ok);
  REQUIRE_THAT(c.why, Catch::Contains("topology"));
  // Six triangles in the ring colour.
  Mesh six = cells_only(2, 6, {0, 1, 2, 1, 2, 3, 2, 3, 4, 3, 4, 5, 4, 5, 0, 5, 0, 1});
  Colouring c6 = colour_mesh(six);
  REQUIRE(c6.ok);
  REQUIRE(check_colouring(six, c6.colour).empty());
}

TEST_CASE("colouring: check_colouring names the cell with two equal colours", "[colour][3d]") {
  Mesh m = generate_kuhn(3, 2);
  Colouring c = colour_mesh(m);
  REQUIRE(c.ok);
  std::vector<std::uint8_t> bad = c.colour;
  const VertexId *x = m.cell(5);
  bad[x[2]] = bad[x[0]];
  std::string why = check_colouring(m, bad);
  REQUIRE_THAT(why, Catch::Contains("of colour " + std::to_string(bad[x[0]])));
  bad = c.colour;
  bad[x[1]] = 4;
  REQUIRE_THAT(check_colouring(m, bad), Catch::Contains("outside 0..3"));
  REQUIRE_THAT(check_colouring(m, std::vector<std::uint8_t>(3, 0)), Catch::Contains("values for"));
}

TEST_CASE("colouring: the point array is read, validated and written", "[colour]") {
  Mesh m = generate_kuhn(2, 2);
  REQUIRE_FALSE(colour_array(m));
  Colouring c = colour_mesh(m);
  set_colour_array(m, c.colour);
  set_colour_array(m, c.colour); // replaces, does not duplicate
  REQUIRE(m.point_data.size() == 1);
  REQUIRE(*colour_array(m) == c.colour);
  m.point_data[0].values[3] = 0.5;
  REQUIRE_THROWS_WITH(colour_array(m), Catch::Contains("vertex 3"));
  m.point_data[0].values[3] = 3;
  REQUIRE_THROWS_AS(colour_array(m), InputError);
}

TEST_CASE("colouring: components that touch at vertices are reconciled", "[colour][3d][2d]") {
  // Two disjoint cubes.
  Mesh a = testing::renumbered(generate_kuhn(3, 2), 3);
  Mesh two = a;
  for (VertexId v : a.cells)
    two.cells.push_back(v + VertexId(a.num_vertices()));
  two.coords.insert(two.coords.end(), a.coords.begin(), a.coords.end());
  for (std::size_t i = a.coords.size(); i < two.coords.size(); i += 3)
    two.coords[i] += 2.0;
  Colouring c2 = colour_mesh(two);
  REQUIRE(c2.ok);
  REQUIRE(c2.components == 2);
  REQUIRE(check_colouring(two, c2.colour).empty());

  // Three triangles touching only at vertices, where the first choice of
  // colours fails: T0 = {0,1,2}, T1 = {0,3,4}, T2 = {3,1,5}; T1 must give 3
  // the colour of neither 0 nor 1.
  Mesh pinched = cells_only(2, 6, {0, 1, 2, 0, 3, 4, 3, 1, 5});
  Colouring cp = colour_mesh(pinched);
  INFO(cp.why);
  REQUIRE(cp.ok);
  REQUIRE(cp.components == 3);
  REQUIRE(check_colouring(pinched, cp.colour).empty());

  // Ten tetrahedra, one per pair of the vertices 0..4 (K5 on the shared
  // vertices): 4 colours cannot separate five mutually joined vertices.
  std::vector<VertexId> cells;
  VertexId next = 5;
  for (VertexId i = 0; i < 5; ++i)
    for (VertexId j = i + 1; j < 5; ++j) {
      cells.insert(cells.end(), {i, j, next, VertexId(next + 1)});
      next += 2;
    }
  Colouring k5 = colour_mesh(cells_only(3, next, cells));
  REQUIRE_FALSE(k5.ok);
  REQUIRE_THAT(k5.why, Catch::Contains("cannot agree"));
}

TEST_CASE("colouring: a facet in three cells is reported", "[colour][2d]") {
  Colouring c = colour_mesh(cells_only(2, 5, {0, 1, 2, 0, 1, 3, 0, 1, 4}));
  REQUIRE_FALSE(c.ok);
  REQUIRE_THAT(c.why, Catch::Contains("more than two cells"));
}

TEST_CASE("barycentric subdivision: always colourable, same volume, boundary and topology",
          "[colour][2d][3d]") {
  std::vector<Mesh> inputs;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    inputs.push_back(
        testing::renumbered(testing::perturbed_inside_box(generate_kuhn(2, 3), 0.08, seed), seed));
    inputs.push_back(
        testing::renumbered(testing::perturbed_inside_box(generate_kuhn(3, 2), 0.08, seed), seed));
  }
  inputs.push_back(tets_around_edge(5));
  inputs.push_back(triangles_around_vertex(7));
  Mesh square = read_mesh(testing::data_path("square.msh"));
  prepare_input(square, "square");
  inputs.push_back(square);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    Mesh in = inputs[i];
    prepare_input(in, "input");
    // A linear point field and a cell field to follow.
    DataArray f{"f", 1, {}};
    for (std::size_t v = 0; v < in.num_vertices(); ++v)
      f.values.push_back(in.point(VertexId(v))[0] + 2 * in.point(VertexId(v))[1] - 0.5);
    in.point_data.push_back(f);
    DataArray id{"id", 1, {}};
    for (std::size_t c = 0; c < in.num_cells(); ++c)
      id.values.push_back(double(c));
    in.cell_data.push_back(id);
    const Invariants inv = measure_invariants(in);

    std::vector<std::uint8_t> colour;
    Mesh b = barycentric_subdivision(in, &colour);
    INFO("input " << i << " (" << in.dim << "D, " << in.num_cells() << " cells)");
    REQUIRE(b.num_cells() == in.num_cells() * (in.dim == 3 ? 24 : 6));
    REQUIRE(check_colouring(b, colour).empty());
    REQUIRE(*colour_array(b) == colour);
    REQUIRE_CONFORMING(b, inv);
    // Propagation finds a colouring too (the subdivision's is unique up to names).
    Colouring c = colour_mesh(b);
    INFO(c.why);
    REQUIRE(c.ok);
    // Positively oriented, and each sub-cell lies in its parent (same id).
    double pts[16];
    for (std::size_t s = 0; s < b.num_cells(); ++s) {
      cell_points(b, CellId(s), pts);
      REQUIRE(signed_volume(pts, b.dim) > 0);
    }
    const DataArray &bid = array_named(b.cell_data, "id");
    for (std::size_t s = 0; s < b.num_cells(); ++s)
      REQUIRE(bid.values[s] == double(s / (in.dim == 3 ? 24 : 6)));
    // Point data interpolated linearly: f is exact at every new vertex.
    const DataArray &bf = array_named(b.point_data, "f");
    for (std::size_t v = 0; v < b.num_vertices(); ++v)
      REQUIRE(bf.values[v] ==
              Approx(b.point(VertexId(v))[0] + 2 * b.point(VertexId(v))[1] - 0.5).margin(1e-12));
    REQUIRE(total_volume(b) == Approx(inv.volume).epsilon(1e-12));
  }
}

TEST_CASE("barycentric subdivision of the ball colours 144k tets quickly", "[colour][3d]") {
  Mesh ball = read_mesh(testing::data_path("ball.msh"));
  prepare_input(ball, "ball");
  REQUIRE_FALSE(colour_mesh(ball).ok);
  const Invariants inv = measure_invariants(ball);
  auto t0 = std::chrono::steady_clock::now();
  Mesh b = barycentric_subdivision(ball);
  auto t1 = std::chrono::steady_clock::now();
  Colouring c = colour_mesh(b);
  auto t2 = std::chrono::steady_clock::now();
  REQUIRE(c.ok);
  REQUIRE(check_colouring(b, c.colour).empty());
  REQUIRE(b.num_cells() == 24 * ball.num_cells());
  REQUIRE(total_volume(b) == Approx(inv.volume).epsilon(1e-12));
  std::cout << "barycentric subdivision of ball.msh: " << b.num_cells() << " tets in "
            << std::chrono::duration<double>(t1 - t0).count() << " s; colouring by propagation "
            << std::chrono::duration<double>(t2 - t1).count() << " s\n";
}
