// Tests for src/check.cpp: invariants, conformity, input validation.
#include "bisect/check.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/threads.hpp"
#include "measure/check_testing.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <vector>

using namespace bisect;
using Catch::Contains;
using Catch::StartsWith;

namespace {

Mesh make_mesh(int dim, std::vector<double> coords, std::vector<VertexId> cells) {
  Mesh m;
  m.dim = dim;
  m.coords = std::move(coords);
  m.cells = std::move(cells);
  return m;
}

double factorial(int n) {
  return n <= 1 ? 1 : n * factorial(n - 1);
}

VertexId add_vertex(Mesh &m, const std::vector<double> &x) {
  m.coords.insert(m.coords.end(), x.begin(), x.end());
  return VertexId(m.num_vertices() - 1);
}

// In the Kuhn cube [0,1]^dim (k = 1) every cell contains the main diagonal
// from vertex 0 to vertex 2^dim - 1. Returns the local index in cell 0 of a
// vertex off that diagonal: the facet opposite it is interior.
int off_diagonal_local(const Mesh &m) {
  const VertexId last = VertexId(m.num_vertices() - 1);
  for (int i = 0; i <= m.dim; ++i)
    if (m.cell(0)[i] != 0 && m.cell(0)[i] != last)
      return i;
  return -1;
}

// Bisects cell 0 of a k = 1 Kuhn cube by the main diagonal, leaving every
// other cell (they all contain the diagonal) with a hanging midpoint.
VertexId bisect_first_cell_by_diagonal(Mesh &m) {
  const int n = m.dim + 1;
  const VertexId last = VertexId(m.num_vertices() - 1);
  const VertexId mid = add_vertex(m, std::vector<double>(m.dim, 0.5));
  std::vector<VertexId> a(m.cell(0), m.cell(0) + n), b = a;
  std::replace(a.begin(), a.end(), last, mid);
  std::replace(b.begin(), b.end(), VertexId(0), mid);
  std::copy(a.begin(), a.end(), m.cell(0));
  m.cells.insert(m.cells.end(), b.begin(), b.end());
  return mid;
}

std::string prepare_error(Mesh m, const std::string &path) {
  try {
    prepare_input(m, path);
  } catch (const InputError &e) {
    return e.what();
  }
  return "no error";
}

} // namespace

TEST_CASE("check: invariants of a single cartesian simplex", "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Invariants inv = measure_invariants(generate_simplex(dim, SimplexShape::Cartesian));
  CHECK(inv.volume == Approx(1.0 / factorial(dim)));
  CHECK(inv.boundary_facets == std::size_t(dim + 1));
  // dim facets in the coordinate hyperplanes, and the slanted one of measure sqrt(n)/(n-1)!.
  CHECK(inv.boundary_measure == Approx((dim + std::sqrt(double(dim))) / factorial(dim - 1)));
  CHECK(inv.euler == 1);
}

TEST_CASE("check: a Kuhn mesh passes against its own invariants, also after relabelling",
          "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  Mesh m = generate_kuhn(dim, 2);
  const Invariants inv = measure_invariants(m);
  CHECK(check_conformity(m).ok);
  // Reverse the vertex numbering: nothing geometric changes.
  const VertexId nv = VertexId(m.num_vertices());
  Mesh r = m;
  for (VertexId &v : r.cells)
    v = nv - 1 - v;
  for (VertexId v = 0; v < nv; ++v)
    std::copy(m.point(v), m.point(v) + dim, r.coords.begin() + std::size_t(nv - 1 - v) * dim);
  const CheckResult res = check_conformity(r, &inv);
  INFO(res.failure);
  CHECK(res.ok);
}

TEST_CASE("check: a cell listed twice is reported as such, with its Gmsh groups",
          "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  Mesh m = generate_kuhn(dim, 2);
  const std::size_t nc = m.num_cells(), n = std::size_t(dim + 1);
  // Cells 3 and 5 again, the second with its vertices in another order.
  for (CellId c : {CellId(3), CellId(5)}) {
    std::vector<VertexId> again(m.cell(c), m.cell(c) + n);
    if (c == 5)
      std::reverse(again.begin(), again.end());
    m.cells.insert(m.cells.end(), again.begin(), again.end());
  }
  INFO("dim " << dim);
  CHECK(prepare_error(m, "twice.vtu") == "twice.vtu: duplicate cells: cells 3 and " +
                                             std::to_string(nc) +
                                             " have the same vertices (and 1 more pairs)");
  // As Gmsh's .msh 2.2 writes a volume in two physical groups.
  DataArray phys{"gmsh:physical", 1, std::vector<double>(nc + 2, 10.0)};
  phys.values[nc] = phys.values[nc + 1] = 11;
  m.cell_data.push_back(phys);
  const std::string e = prepare_error(m, "vol.msh");
  CHECK_THAT(e, StartsWith("vol.msh: duplicate cells: cells 3 and " + std::to_string(nc) +
                           " have the same vertices, with gmsh:physical 10 and 11 (and 1 more "
                           "pairs): Gmsh's .msh 2.2 repeats an element"));
  CHECK_THAT(e, Contains("save as .msh 4.1"));
}

TEST_CASE("check: a facet shared by three cells is found", "[check][2d][3d][4d]") {
  SECTION("2D by hand") {
    Mesh m = make_mesh(2, {0, 0, 1, 0, 0.5, 1, 0.5, -1, 0.5, 2}, {0, 1, 2, 1, 0, 3, 0, 1, 4});
    const CheckResult r = check_conformity(m);
    CHECK_FALSE(r.ok);
    CHECK(r.failure == "facet (0, 1) is shared by 3 cells");
    CHECK(prepare_error(m, "fan.msh") == "fan.msh: non-manifold: facet (0, 1) shared by 3 cells");
  }
  SECTION("a third cell on an interior facet of a Kuhn cube") {
    const int dim = GENERATE(2, 3, 4);
    Mesh m = generate_kuhn(dim, 1);
    const int skip = off_diagonal_local(m);
    std::vector<VertexId> extra;
    for (int i = 0; i <= dim; ++i)
      if (i != skip)
        extra.push_back(m.cell(0)[i]);
    std::vector<double> far(dim, 3.0);
    far[0] = -2.0;
    extra.push_back(add_vertex(m, far));
    m.cells.insert(m.cells.end(), extra.begin(), extra.end());
    const CheckResult r = check_conformity(m);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.failure, StartsWith("facet (") && Contains(") is shared by 3 cells"));
    CHECK_THAT(prepare_error(m, "k.vtu"), StartsWith("k.vtu: non-manifold: facet ("));
  }
}

TEST_CASE("check: a tangled mesh (two overlapping cells) is rejected", "[check][2d][3d][4d]") {
  SECTION("2D by hand") {
    // Both opposite vertices of edge (0, 1) lie above it.
    Mesh m = make_mesh(2, {0, 0, 1, 0, 0, 1, 0.4, 0.4}, {0, 1, 2, 1, 0, 3});
    const CheckResult r = check_conformity(m);
    CHECK_FALSE(r.ok);
    CHECK(r.failure == "cells 0 and 1 overlap across facet (0, 1)");
    CHECK(prepare_error(m, "t.vtu") == "t.vtu: tangled: cells 0 and 1 overlap across facet (0, 1)");
  }
  SECTION("a Kuhn cell folded onto its neighbour") {
    const int dim = GENERATE(2, 3, 4);
    Mesh m = generate_kuhn(dim, 1);
    const int skip = off_diagonal_local(m);
    const VertexId opposite = m.cell(0)[skip];
    std::vector<VertexId> facet;
    for (int i = 0; i <= dim; ++i)
      if (i != skip)
        facet.push_back(m.cell(0)[i]);
    // P halfway between the facet's centroid and cell 0's opposite vertex:
    // on cell 0's side of the facet.
    std::vector<double> p(dim, 0.0);
    for (VertexId v : facet)
      for (int d = 0; d < dim; ++d)
        p[d] += m.point(v)[d] / dim;
    for (int d = 0; d < dim; ++d)
      p[d] = 0.5 * (p[d] + m.point(opposite)[d]);
    const VertexId pv = add_vertex(m, p);
    // The neighbour across the facet now uses P instead of its own opposite vertex.
    bool moved = false;
    for (CellId c = 1; c < m.num_cells() && !moved; ++c) {
      VertexId *cell = m.cell(c);
      const int shared = int(std::count_if(facet.begin(), facet.end(), [&](VertexId v) {
        return std::find(cell, cell + dim + 1, v) != cell + dim + 1;
      }));
      if (shared != dim)
        continue;
      for (int i = 0; i <= dim; ++i)
        if (std::find(facet.begin(), facet.end(), cell[i]) == facet.end())
          cell[i] = pv;
      moved = true;
    }
    REQUIRE(moved);
    const CheckResult r = check_conformity(m);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.failure, StartsWith("cells 0 and ") && Contains(" overlap across facet ("));
    CHECK_THAT(prepare_error(m, "k.vtu"), StartsWith("k.vtu: tangled: cells 0 and "));
  }
}

TEST_CASE("angle condition: the fuzzer's tangled inputs (one cell id changed) are rejected",
          "[check][io][2d][3d]") {
  const std::string dir = std::string(BISECT_DATA_DIR) + "/../fuzz/findings/minimized/";
  for (const char *name : {"wrong-overlap-2d.msh", "wrong-overlap-3d.vtu"}) {
    INFO(name);
    const Mesh m = read_mesh(dir + name);
    CHECK_THAT(prepare_error(m, name),
               StartsWith(std::string(name) + ": tangled: the ") && Contains(" cells around "));
  }
}

TEST_CASE("angle condition: every single vertex id changed in a Kuhn mesh is rejected, some by "
          "the angle sums alone",
          "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh kuhn = generate_kuhn(dim, dim == 2 ? 3 : 2);
  const std::size_t stride = dim == 4 ? 29 : 1; // 4D: 14 of the 384 cells
  REQUIRE(prepare_error(kuhn, "k.vtu") == "no error");
  const int n = dim + 1;
  int changes = 0, by_angles = 0;
  for (std::size_t c = 0; c < kuhn.num_cells(); c += stride)
    for (int i = 0; i < n; ++i)
      for (VertexId v = 0; v < kuhn.num_vertices(); ++v) {
        const VertexId *cell = kuhn.cell(CellId(c));
        if (std::find(cell, cell + n, v) != cell + n)
          continue;
        Mesh m = kuhn;
        m.cell(CellId(c))[i] = v;
        const std::string e = prepare_error(m, "k.vtu");
        INFO("cell " << c << " local vertex " << i << " -> " << v << ": " << e);
        // The changed cell overlaps cells that are all still there (the
        // domain is convex), is flat, or is now another cell again.
        CHECK((StartsWith("k.vtu: tangled: ").match(e) || Contains("zero volume").match(e) ||
               Contains("non-manifold").match(e) || Contains("non-conforming").match(e) ||
               StartsWith("k.vtu: duplicate cells: ").match(e)));
        ++changes;
        by_angles += Contains(" cells around ").match(e);
      }
  CHECK(changes > 0);
  CHECK(by_angles > 0);
}

TEST_CASE("angle condition: a star that turns twice around an interior face is rejected by the "
          "angle sum alone",
          "[check][2d][3d][4d]") {
  // Five cells around a face F (a vertex, an edge, a triangle) whose
  // vertices off F, p_i at 144 i degrees, turn twice around it: every facet
  // through F is in two cells on opposite sides, no centroid lies strictly
  // inside another cell (each lies on a ray another cell has as its edge),
  // and the boundary (a pentagram) has no vertex on it: only the 720
  // degrees around F tell.
  const int dim = GENERATE(2, 3, 4);
  Mesh m;
  m.dim = dim;
  std::vector<VertexId> face;
  if (dim == 2)
    face.push_back(add_vertex(m, {0, 0}));
  if (dim == 3)
    for (double z : {-1.0, 1.0})
      face.push_back(add_vertex(m, {0, 0, z}));
  if (dim == 4)
    for (const std::vector<double> &zw :
         std::vector<std::vector<double>>{{-1, -1}, {2, -1}, {-1, 2}})
      face.push_back(add_vertex(m, {0, 0, zw[0], zw[1]}));
  std::vector<VertexId> ring;
  for (int i = 0; i < 5; ++i) {
    std::vector<double> p(static_cast<std::size_t>(dim), 0.0);
    p[0] = std::cos(i * 0.8 * M_PI);
    p[1] = std::sin(i * 0.8 * M_PI);
    ring.push_back(add_vertex(m, p));
  }
  for (int i = 0; i < 5; ++i) {
    m.cells.insert(m.cells.end(), face.begin(), face.end());
    m.cells.push_back(ring[std::size_t(i)]);
    m.cells.push_back(ring[std::size_t((i + 1) % 5)]);
  }
  INFO("dim " << dim);
  const std::string e = prepare_error(m, "t.vtu");
  CHECK_THAT(e, StartsWith("t.vtu: tangled: the 5 cells around "));
  CHECK_THAT(e, Contains("720"));
}

TEST_CASE("angle condition: valid meshes pass (Kuhn, perturbed, reoriented, refined, graded)",
          "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const int k = dim == 4 ? 2 : 4;
  Mesh m = generate_kuhn(dim, k);
  REQUIRE_NOTHROW(prepare_input(m, "kuhn.vtu"));
  // Perturb the interior vertices by up to 0.05 of the spacing, deterministically.
  std::uint64_t state = 12345;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53) - 0.5;
  };
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    double *x = &m.coords[v * dim];
    bool interior = true;
    for (int d = 0; d < dim; ++d)
      interior = interior && x[d] > 1e-9 && x[d] < 1 - 1e-9;
    if (interior)
      for (int d = 0; d < dim; ++d)
        x[d] += 0.1 * next() / k;
  }
  // Flip some cells (prepare_input orients them).
  for (std::size_t c = 0; c < m.num_cells(); c += 3)
    std::swap(m.cell(CellId(c))[0], m.cell(CellId(c))[1]);
  REQUIRE_NOTHROW(prepare_input(m, "perturbed.vtu"));
  mark_mesh(m, Marking::Longest);
  refine_uniform(m);
  Mesh copy = m;
  REQUIRE_NOTHROW(prepare_input(copy, "refined.vtu"));
  // Graded: refine the cells near one corner twice more.
  for (int round = 0; round < 2; ++round) {
    std::vector<CellId> near;
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      if (m.point(m.cell(CellId(c))[0])[0] < 0.3)
        near.push_back(CellId(c));
    refine(m, near);
  }
  REQUIRE_NOTHROW(prepare_input(m, "graded.vtu"));
}

TEST_CASE("check: a hanging node is rejected by prepare_input", "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  Mesh m = generate_kuhn(dim, 1);
  const Invariants before = measure_invariants(m);
  const VertexId mid = bisect_first_cell_by_diagonal(m);
  const std::string err = prepare_error(m, "h.vtu");
  CHECK_THAT(err, StartsWith("h.vtu: non-conforming input: vertex " + std::to_string(mid) +
                             " lies on facet (") &&
                      Contains("(hanging node)"));
  const CheckResult r = check_conformity(m, &before);
  CHECK_FALSE(r.ok);
  CHECK_THAT(r.failure, Contains("hanging node"));
  // The volume alone does not see it.
  CHECK(measure_invariants(m).volume == Approx(before.volume));
}

TEST_CASE("check: a square bisected by hand with a hanging hypotenuse midpoint is non-conforming",
          "[check][2d]") {
  // Square (0,1,2,3) split along the diagonal (0,2) into two triangles; then
  // the lower one is bisected at the diagonal's midpoint 4, the upper is not.
  const Mesh square = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1}, {0, 1, 2, 0, 2, 3});
  const Invariants before = measure_invariants(square);
  CHECK(before.euler == 1);
  CHECK(before.boundary_measure == Approx(4));
  Mesh m = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5}, {0, 1, 4, 1, 2, 4, 0, 2, 3});

  CHECK(prepare_error(m, "square.vtu") ==
        "square.vtu: non-conforming input: vertex 4 lies on facet (0, 2) (hanging node)");
  const CheckResult r = check_conformity(m, &before);
  CHECK_FALSE(r.ok);
  CHECK(r.failure == "vertex 4 lies on facet (0, 2) (hanging node)");
  // Every facet has at most two cells and the volume is unchanged, but the
  // invariants see the crack: Euler characteristic 0, boundary longer by 2 sqrt 2.
  const Invariants after = measure_invariants(m);
  CHECK(after.volume == Approx(1));
  CHECK(after.euler == 0);
  CHECK(after.boundary_measure == Approx(4 + 2 * std::sqrt(2.0)));
}

TEST_CASE("names: messages name a .msh input's node and element tags, .vtu's indices",
          "[check][io][2d]") {
  // The square bisected by hand above, as a .msh with nodes tagged 101 +
  // 104 v and elements 17 + 6 c, stored as lists (not an offset).
  Mesh m = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5}, {0, 1, 4, 1, 2, 4, 0, 2, 3});
  CHECK(prepare_error(m, "s.vtu") ==
        "s.vtu: non-conforming input: vertex 4 lies on facet (0, 2) (hanging node)");
  m.numbering.gmsh = true;
  m.numbering.vertices = 5;
  m.numbering.cells = 3;
  m.numbering.node_tags = {101, 205, 309, 413, 517};
  m.numbering.element_tags = {17, 23, 29};
  CHECK(prepare_error(m, "s.msh") ==
        "s.msh: non-conforming input: node 517 lies on facet of nodes (101, 309) (hanging node)");
  CHECK(check_conformity(m).failure == "node 517 lies on facet of nodes (101, 309) (hanging node)");
  SECTION("tags that run from an offset are stored as the offset") {
    m.numbering.node_tags.clear();
    m.numbering.node_base = 1000;
    CHECK(prepare_error(m, "s.msh") ==
          "s.msh: non-conforming input: node 1004 lies on facet of nodes (1000, 1002) (hanging "
          "node)");
  }
  SECTION("a numbering not sized for the mesh is not used") {
    m.numbering.cells = 4;
    CHECK(prepare_error(m, "s.msh") ==
          "s.msh: non-conforming input: vertex 4 lies on facet (0, 2) (hanging node)");
  }
  SECTION("cells by element tag") {
    m.cells[1] = 4; // cell 0 repeats vertex 4
    CHECK(prepare_error(m, "s.msh") == "s.msh: element 17 repeats node 517");
  }
}

TEST_CASE("names: refinement drops the file's numbering", "[check][2d]") {
  Mesh m = generate_kuhn(2, 1);
  m.numbering.gmsh = true;
  m.numbering.vertices = m.num_vertices();
  m.numbering.cells = m.num_cells();
  mark_mesh(m, Marking::Index);
  refine_uniform(m);
  CHECK_FALSE(m.numbering.gmsh);
}

TEST_CASE("duplicates: coincident vertices are reported as such, whichever check fails first",
          "[check][2d]") {
  // A square whose two triangles do not share their diagonal (vertices 4, 5
  // repeat 0 and 2): each check sees a hanging node.
  Mesh m = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 1}, {0, 1, 2, 4, 5, 3});
  CHECK_THAT(prepare_error(m, "d.vtu"), StartsWith("d.vtu: duplicate vertices: 0 and 4 are both "
                                                   "at (0, 0) (and 1 more pairs)"));
  // A flat triangle made of two coincident vertices: zero volume first.
  Mesh flat = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 1, 0}, {0, 1, 2, 0, 2, 3, 1, 4, 2});
  CHECK_THAT(prepare_error(flat, "f.vtu"),
             StartsWith("f.vtu: duplicate vertices: 1 and 4 are both at (1, 0)"));
}

TEST_CASE("check: hanging vertices that are not edge midpoints are caught too", "[check][2d][3d]") {
  SECTION("2D: the square split at a third of its diagonal") {
    Mesh m = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 1.0 / 3, 1.0 / 3}, {0, 1, 4, 1, 2, 4, 0, 2, 3});
    CHECK_THAT(prepare_error(m, "s.vtu"), Contains("vertex 4 lies on facet (0, 2) (hanging node)"));
  }
  SECTION("3D: a face centre, on no edge at all") {
    // Tets above and below triangle (0,1,2); the upper one is split into three
    // by the centroid 5 of that triangle, the lower one is not.
    Mesh m =
        make_mesh(3, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.2, 0.2, -1, 1.0 / 3, 1.0 / 3, 0},
                  {0, 1, 5, 3, 1, 2, 5, 3, 2, 0, 5, 3, 0, 1, 2, 4});
    CHECK(prepare_error(m, "f.vtu") ==
          "f.vtu: non-conforming input: vertex 5 lies on facet (0, 1, 2) (hanging node)");
    CHECK_THAT(check_conformity(m).failure, Contains("hanging node"));
  }
}

TEST_CASE("check: negatively oriented cells are reoriented, not rejected", "[check][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh kuhn = generate_kuhn(dim, 2);
  Mesh m = kuhn;
  for (std::size_t c = 0; c < m.num_cells(); c += 2)
    std::swap(m.cell(CellId(c))[0], m.cell(CellId(c))[1]);
  CHECK(check_conformity(m).ok); // orientation is not a conformity property
  REQUIRE_NOTHROW(prepare_input(m, "neg.vtu"));
  CHECK(m.cells == kuhn.cells);
  CHECK(m.coords == kuhn.coords);
  std::vector<double> p((dim + 1) * dim);
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    cell_points(m, CellId(c), p.data());
    CHECK(signed_volume(p.data(), dim) > 0);
  }
}

TEST_CASE("check: a changed volume is reported", "[check][3d]") {
  Mesh m = generate_kuhn(3, 2, 0.0, 2.0);
  const Invariants inv = measure_invariants(m);
  Mesh scaled = m;
  for (double &x : scaled.coords)
    x *= 1 + 1e-4;
  CheckResult r = check_conformity(scaled, &inv);
  CHECK_FALSE(r.ok);
  CHECK_THAT(r.failure, StartsWith("volume changed: 8 -> 8.002") && Contains("(relative 0.0003)"));
  // Within the relative tolerance 1e-9 nothing is reported.
  for (double &x : m.coords)
    x *= 1 + 1e-12;
  r = check_conformity(m, &inv);
  INFO(r.failure);
  CHECK(r.ok);
}

TEST_CASE("check: changed boundary measure and Euler characteristic are reported", "[check][2d]") {
  const Mesh m = generate_kuhn(2, 3);
  Invariants inv = measure_invariants(m);
  Invariants wrong = inv;
  wrong.boundary_measure *= 1.5;
  CHECK_THAT(check_conformity(m, &wrong).failure, StartsWith("boundary measure changed: 6 -> 4"));
  wrong = inv;
  wrong.euler = 2;
  CHECK(check_conformity(m, &wrong).failure == "Euler characteristic changed: 2 -> 1");

  // A real change of topology: remove the two centre triangles (an annulus).
  Mesh annulus = m;
  annulus.cells.clear();
  std::vector<double> p(6);
  for (CellId c = 0; c < m.num_cells(); ++c) {
    cell_points(m, c, p.data());
    const double cx = (p[0] + p[2] + p[4]) / 3, cy = (p[1] + p[3] + p[5]) / 3;
    if (cx > 1.0 / 3 && cx < 2.0 / 3 && cy > 1.0 / 3 && cy < 2.0 / 3)
      continue;
    annulus.cells.insert(annulus.cells.end(), m.cell(c), m.cell(c) + 3);
  }
  CHECK(annulus.num_cells() == m.num_cells() - 2);
  CHECK(measure_invariants(annulus).euler == 0);
  CHECK(check_conformity(annulus).ok);
}

TEST_CASE("check: a degenerate cell is reported with its index", "[check][2d]") {
  Mesh m = make_mesh(2, {0, 0, 1, 0, 0, 1, 2, 0, 0.5, 1e-15}, {0, 1, 2, 1, 3, 4});
  CHECK_THAT(check_conformity(m).failure, StartsWith("cell 1 is degenerate (volume "));
  CHECK(prepare_error(m, "d.msh") == "d.msh: cell 1 has zero volume");
}

TEST_CASE("prepare_input rejects bad coordinates and ids, naming the file and the entity",
          "[check][2d]") {
  const Mesh good = make_mesh(2, {0, 0, 1, 0, 0, 1}, {0, 1, 2});
  SECTION("non-finite coordinate") {
    Mesh m = good;
    m.coords[3] = std::numeric_limits<double>::quiet_NaN();
    CHECK(prepare_error(m, "a.msh") == "a.msh: vertex 1 has a non-finite coordinate");
    m.coords[3] = std::numeric_limits<double>::infinity();
    CHECK(prepare_error(m, "a.msh") == "a.msh: vertex 1 has a non-finite coordinate");
  }
  SECTION("id out of range") {
    Mesh m = good;
    m.cells[2] = 7;
    CHECK(prepare_error(m, "a.msh") ==
          "a.msh: cell 0 refers to vertex 7, but there are only 3 vertices");
  }
  SECTION("repeated vertex") {
    Mesh m = good;
    m.cells[2] = 1;
    CHECK(prepare_error(m, "a.msh") == "a.msh: cell 0 repeats vertex 1");
  }
  SECTION("good input passes and keeps its marks") {
    Mesh m = good;
    m.stage = {Stage::Maubach};
    m.tag = {2};
    REQUIRE_NOTHROW(prepare_input(m, "a.msh"));
    CHECK(m.stage == std::vector<Stage>{Stage::Maubach});
    CHECK(m.tag == std::vector<std::uint8_t>{2});
  }
}

TEST_CASE("check: two tets that split their shared face differently, without a hanging node, "
          "are found with or without the original",
          "[check][3d]") {
  // Face ABC (z = 0) between apex P above and apex Q below, with M the
  // midpoint of AB and N that of BC on both sides. Above, the face is cut into
  // MBN, AMC, MNC; below into MBN, AMN, ANC: the same five vertices, no vertex
  // on a facet of the other side, but AMC/MNC and AMN/ANC do not match.
  // Bisection can make this: AB then BC on one side, BC then AB on the other.
  const std::vector<double> xyz = {0,   0,   0, 1,   0,   0, 0, 1, 0, // A B C
                                   0.5, 0,   0, 0.5, 0.5, 0,          // M N
                                   0.3, 0.3, 1, 0.3, 0.3, -1};        // P Q
  enum : VertexId { A, B, C, M, N, P, Q };
  const Mesh original = make_mesh(3, xyz, {A, B, C, P, A, B, C, Q});
  const Invariants before = measure_invariants(original);
  REQUIRE(check_conformity(original).ok);

  const Mesh split = make_mesh(3, xyz, {P, M, B, N, P, A, M, C, P, M, N, C,   // above
                                        Q, M, B, N, Q, A, M, N, Q, A, N, C}); // below
  const CheckResult c = check_conformity(split);
  CHECK_FALSE(c.ok);
  CHECK_THAT(c.failure, Contains("overlap: the cells on the two sides of a face split it "
                                 "differently"));
  CHECK_THAT(c.failure, StartsWith("boundary facets ("));
  // Volume is kept; the unmatched patches count as boundary on both sides.
  const Invariants after = measure_invariants(split);
  CHECK(after.volume == Approx(before.volume).epsilon(1e-12));
  CHECK(after.boundary_measure == Approx(before.boundary_measure + 2 * 0.375).epsilon(1e-12));
  CHECK_THAT(check_conformity(split, &before).failure, Contains("overlap"));
  // With the measure standing in for the search (CheckOptions), the same mesh
  // fails through its boundary measure.
  CheckOptions refined;
  refined.refined_from_original = true;
  CHECK_THAT(check_conformity(split, &before, refined).failure,
             StartsWith("boundary measure changed"));
  // Reading such a mesh is refused too.
  CHECK_THAT(prepare_error(split, "split.vtu"),
             StartsWith("split.vtu: non-conforming input: boundary facets ("));

  // The same five vertices split alike on both sides: conforming, and the
  // search stays quiet.
  const Mesh alike = make_mesh(3, xyz, {P, M, B, N, P, A, M, C, P, M, N, C,   // above
                                        Q, M, B, N, Q, A, M, C, Q, M, N, C}); // below
  CHECK(check_conformity(alike).ok);
  CHECK(check_conformity(alike, &before).ok);
  CHECK(check_conformity(alike, &before, refined).ok);
}

TEST_CASE("final check: check_refined catches a hanging node, a split face, a degenerate and an "
          "inverted cell, and passes honest refinements",
          "[check][2d][3d]") {
  // The hand-made hanging hypotenuse midpoint (2D).
  const Mesh square = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1}, {0, 1, 2, 0, 2, 3});
  const Invariants sq = measure_invariants(square, false);
  const Mesh hanging =
      make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5}, {0, 1, 4, 1, 2, 4, 0, 2, 3});
  CHECK_THAT(check_refined(hanging, sq).failure, StartsWith("boundary measure changed"));
  // A degenerate cell, and an inverted one (folded across the diagonal).
  const Mesh flat = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5}, {0, 1, 2, 0, 2, 3, 0, 4, 2});
  CHECK_THAT(check_refined(flat, sq).failure, Contains("degenerate"));
  const Mesh folded = make_mesh(2, {0, 0, 1, 0, 1, 1, 0, 1, 0.8, 0.3}, {0, 1, 2, 0, 2, 4});
  CHECK_THAT(check_refined(folded, sq).failure, Contains("overlap"));
  // The face split differently from its two sides (3D), no hanging node.
  const std::vector<double> xyz = {0, 0,   0,   1, 0,   0,   0, 1,   0,   0.5, 0,
                                   0, 0.5, 0.5, 0, 0.3, 0.3, 1, 0.3, 0.3, -1};
  enum : VertexId { A, B, C, M, N, P, Q };
  const Invariants two = measure_invariants(make_mesh(3, xyz, {A, B, C, P, A, B, C, Q}), false);
  const Mesh split =
      make_mesh(3, xyz, {P, M, B, N, P, A, M, C, P, M, N, C, Q, M, B, N, Q, A, M, N, Q, A, N, C});
  CHECK_THAT(check_refined(split, two).failure, StartsWith("boundary measure changed"));
  const Mesh alike =
      make_mesh(3, xyz, {P, M, B, N, P, A, M, C, P, M, N, C, Q, M, B, N, Q, A, M, C, Q, M, N, C});
  CHECK(check_refined(alike, two).ok);
  // Honest refinements pass.
  for (int dim : {2, 3, 4}) {
    Mesh m = generate_kuhn(dim, 2);
    mark_mesh(m, Marking::Index);
    const Invariants inv = measure_invariants(m, false);
    refine_uniform(m);
    refine(m, {0, 1, 2});
    INFO("dim " << dim);
    CHECK(check_refined(m, inv).ok);
    // An id out of range, named (not read: the sanitizer build would see),
    // at the start, in the middle (another block of the cell pass) and at
    // the end of the cells.
    refine_uniform(m);
    while (m.num_cells() < 40000)
      refine_uniform(m);
    const std::size_t nc = m.num_cells(), nv = m.num_vertices();
    for (std::size_t c : {std::size_t(0), nc / 2 + 3, nc - 1}) {
      Mesh bad = m;
      bad.cells[c * std::size_t(dim + 1) + 1] = VertexId(nv + 5);
      CHECK(check_refined(bad, inv).failure ==
            "cell " + std::to_string(c) + " refers to vertex " + std::to_string(nv + 5) +
                ", but there are only " + std::to_string(nv) + " vertices");
    }
  }
}

TEST_CASE("checks: the same volumes, measures, verdicts and messages for 1, 2 and 3 threads",
          "[check][threads][3d]") {
  // Large enough for every parallel path: more than 131,072 cells (two
  // parts of the scan), thousands of coarse buckets (many visitor blocks).
  Mesh m = generate_kuhn(3, 12);
  mark_mesh(m, Marking::Index);
  const Invariants original = measure_invariants(m, true);
  while (m.num_cells() < 140000)
    refine_uniform(m);
  // A broken copy: one cell's vertex moved onto a neighbour's (a fold and a
  // hanging node at once), found by the walk, not by the cell pass.
  Mesh broken = m;
  broken.cells[4 * 100000 + 1] = broken.cells[4 * 100001 + 2];
  INFO(m.num_cells() << " cells");
  std::vector<Invariants> inv;
  std::vector<std::string> verdicts;
  for (int t : {1, 2, 3}) {
    set_threads(t);
    inv.push_back(measure_invariants(m, true));
    const CheckResult good = check_refined(m, original);
    CHECK(good.ok);
    const CheckResult refined = check_refined(broken, original);
    const CheckResult full = check_conformity(broken, &original);
    CHECK(!refined.ok);
    CHECK(!full.ok);
    verdicts.push_back(refined.failure + " | " + full.failure);
  }
  set_threads(0);
  for (std::size_t i = 1; i < inv.size(); ++i) {
    // Bit for bit, not within a tolerance.
    CHECK(inv[i].volume == inv[0].volume);
    CHECK(inv[i].boundary_measure == inv[0].boundary_measure);
    CHECK(inv[i].boundary_facets == inv[0].boundary_facets);
    CHECK(inv[i].euler == inv[0].euler);
    CHECK(verdicts[i] == verdicts[0]);
  }
  CHECK(std::abs(inv[0].volume - original.volume) < 1e-12 * original.volume);
}

TEST_CASE("final check: matching facets by hashing gives the sorted walk's verdicts and messages",
          "[check][threads][2d][3d][4d]") {
  // Meshes of more than 1,024 vertices, so the walk has fine buckets and
  // the hashing path runs; each defect in a copy of its own.
  for (int dim : {2, 3, 4}) {
    Mesh m = generate_kuhn(dim, dim == 2 ? 40 : dim == 3 ? 12 : 6);
    mark_mesh(m, Marking::Index);
    const Invariants original = measure_invariants(m, false);
    while (m.num_cells() < 70000)
      refine_uniform(m);
    REQUIRE(m.num_vertices() > 4096);
    const int n = dim + 1;
    const std::size_t nc = m.num_cells();
    std::vector<std::pair<std::string, Mesh>> cases;
    cases.emplace_back("honest", m);
    Mesh moved = m; // a vertex moved onto a neighbour's: fold and hanging node
    moved.cells[std::size_t(n) * (nc / 2) + 1] = moved.cells[std::size_t(n) * (nc / 2 + 1) + 2];
    cases.emplace_back("moved", std::move(moved));
    Mesh twice = m; // a cell repeated: its facets in three cells, or two on one side
    twice.cells.insert(twice.cells.end(), m.cells.begin() + std::ptrdiff_t(n) * 12345,
                       m.cells.begin() + std::ptrdiff_t(n) * 12346);
    cases.emplace_back("twice", std::move(twice));
    // A cell off the boundary moved last and repeated: each of its facets
    // in three cells, its neighbour's copy first and the two others, on one
    // side, after it (the third copy is what tells them apart).
    Mesh thrice = m;
    {
      auto inside = [&](std::size_t c) {
        for (int i = 0; i < n; ++i)
          for (int d = 0; d < dim; ++d)
            if (const double x = m.point(m.cell(CellId(c))[i])[d]; !(x > 0 && x < 1))
              return false;
        return true;
      };
      std::size_t c = nc / 3;
      while (!inside(c))
        ++c;
      std::swap_ranges(thrice.cells.begin() + std::ptrdiff_t(n) * std::ptrdiff_t(c),
                       thrice.cells.begin() + std::ptrdiff_t(n) * std::ptrdiff_t(c + 1),
                       thrice.cells.end() - n);
      const std::vector<VertexId> last(thrice.cells.end() - n, thrice.cells.end());
      thrice.cells.insert(thrice.cells.end(), last.begin(), last.end());
    }
    cases.emplace_back("thrice", std::move(thrice));
    Mesh holed = m; // a cell removed: a hole, the boundary grows
    holed.cells.erase(holed.cells.begin() + std::ptrdiff_t(n) * 777,
                      holed.cells.begin() + std::ptrdiff_t(n) * 778);
    cases.emplace_back("holed", std::move(holed));
    Mesh pushed = m; // a vertex pushed through its cell's opposite facet: inverted
    {
      const VertexId *c = m.cell(CellId(4242));
      std::vector<double> x(m.point(c[0]), m.point(c[0]) + dim);
      for (int i = 1; i <= dim; ++i)
        for (int d = 0; d < dim; ++d)
          x[std::size_t(d)] += 2.0 / dim * (m.point(c[i])[d] - m.point(c[0])[d]) * 1.5;
      pushed.coords.insert(pushed.coords.end(), x.begin(), x.end());
      pushed.cells[std::size_t(n) * 4242] = VertexId(m.num_vertices());
    }
    cases.emplace_back("pushed", std::move(pushed));
    for (const auto &[what, mesh] : cases) {
      INFO("dim " << dim << ", " << what);
      std::vector<std::string> verdicts;
      // Hashing whole coarse buckets, hashing them in pieces of about 16
      // facets (what a 4D mesh of millions of cells does with 2,048), and
      // the sorted walk.
      // Each also in chunks of 64 KiB (tens of chunks, the per-cell chunk
      // pairs in use) as well as in one; and each with the place in the
      // coarse bucket packed into the entries (what these small meshes get)
      // and beside them (what meshes of many vertices get).
      for (int way : {0, 1, 2})
        for (std::size_t chunk : {std::size_t(0), std::size_t(64) << 10})
          for (bool wide : {false, true})
            for (int t : wide ? std::vector<int>{2} : std::vector<int>{1, 2, 3}) {
              testing::use_sorted_final_walk(way == 2);
              testing::set_final_walk_piece(way == 1 ? 16 : std::size_t(1) << 30);
              testing::set_walk_chunk_bytes(chunk);
              testing::use_wide_final_walk(wide);
              set_threads(t);
              const CheckResult r = check_refined(mesh, original);
              verdicts.push_back(r.ok ? "ok" : r.failure);
            }
      testing::use_wide_final_walk(false);
      testing::use_sorted_final_walk(false);
      testing::set_final_walk_piece(0);
      testing::set_walk_chunk_bytes(0);
      set_threads(0);
      CHECK((what == "honest") == (verdicts[0] == "ok"));
      for (const std::string &v : verdicts)
        CHECK(v == verdicts[0]);
    }
  }
}

namespace {

std::vector<double> centroid_of(const Mesh &m, CellId c) {
  std::vector<double> x(std::size_t(m.dim), 0.0);
  for (int i = 0; i <= m.dim; ++i)
    for (int d = 0; d < m.dim; ++d)
      x[std::size_t(d)] += m.point(m.cell(c)[i])[d] / (m.dim + 1);
  return x;
}

// Whether x lies strictly inside cell c (every barycentric coordinate above
// 1e-9), by elimination on the edge matrix: a second, independent solver.
bool strictly_inside(const Mesh &m, CellId c, const std::vector<double> &x) {
  const int d = m.dim, w = d + 1;
  std::vector<double> a(std::size_t(d * w));
  const double *p0 = m.point(m.cell(c)[0]);
  for (int r = 0; r < d; ++r) {
    for (int j = 0; j < d; ++j)
      a[std::size_t(r * w + j)] = m.point(m.cell(c)[j + 1])[r] - p0[r];
    a[std::size_t(r * w + d)] = x[std::size_t(r)] - p0[r];
  }
  auto at = [&](int r, int j) -> double & { return a[std::size_t(r * w + j)]; };
  for (int k = 0; k < d; ++k) {
    int p = k;
    for (int i = k + 1; i < d; ++i)
      if (std::abs(at(i, k)) > std::abs(at(p, k)))
        p = i;
    for (int j = 0; j <= d; ++j)
      std::swap(at(k, j), at(p, j));
    for (int i = k + 1; i < d; ++i) {
      const double f = at(i, k) / at(k, k);
      for (int j = k; j <= d; ++j)
        at(i, j) -= f * at(k, j);
    }
  }
  std::vector<double> lambda(static_cast<std::size_t>(d));
  double rest = 1;
  for (int k = d - 1; k >= 0; --k) {
    double s = at(k, d);
    for (int j = k + 1; j < d; ++j)
      s -= at(k, j) * lambda[std::size_t(j)];
    lambda[std::size_t(k)] = s / at(k, k);
  }
  for (double l : lambda) {
    if (!(l > 1e-9))
      return false;
    rest -= l;
  }
  return rest > 1e-9;
}

// A graded mesh: the Kuhn mesh refined once, then twice more near x = 0.
Mesh graded_kuhn(int dim, int k) {
  Mesh m = generate_kuhn(dim, k);
  mark_mesh(m, Marking::Longest);
  refine_uniform(m);
  for (int round = 0; round < 2; ++round) {
    std::vector<CellId> near;
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      if (m.point(m.cell(CellId(c))[0])[0] < 0.3)
        near.push_back(CellId(c));
    refine(m, near);
  }
  return m;
}

// Appends a copy of the cell nearest `where` (by centroid), scaled by
// `scale` about its centroid, on vertices of its own: it shares no facet
// with the mesh. Returns the new cell.
CellId add_scaled_copy(Mesh &m, const std::vector<double> &where, double scale) {
  CellId model = 0;
  double best = 1e300;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const std::vector<double> x = centroid_of(m, CellId(c));
    double s = 0;
    for (int d = 0; d < m.dim; ++d)
      s +=
          (x[std::size_t(d)] - where[std::size_t(d)]) * (x[std::size_t(d)] - where[std::size_t(d)]);
    if (s < best)
      best = s, model = CellId(c);
  }
  const std::vector<double> g = centroid_of(m, model);
  std::vector<VertexId> cell;
  for (int i = 0; i <= m.dim; ++i) {
    std::vector<double> p(std::size_t(m.dim));
    for (int d = 0; d < m.dim; ++d)
      p[std::size_t(d)] =
          g[std::size_t(d)] + scale * (m.point(m.cell(model)[i])[d] - g[std::size_t(d)]);
    cell.push_back(add_vertex(m, p));
  }
  m.cells.insert(m.cells.end(), cell.begin(), cell.end());
  return CellId(m.num_cells() - 1);
}

// Case k of the cells laid over a mesh: a copy of the cell nearest a point
// spread over the mesh, scaled by one of four factors (returned).
double lay_cell_over(Mesh &m, int k) {
  std::vector<double> where(static_cast<std::size_t>(m.dim));
  for (int d = 0; d < m.dim; ++d)
    where[std::size_t(d)] = 0.05 + 0.9 * std::fmod(0.37 * (k + 1) * (d + 2), 1.0);
  const double scale = std::array{0.3, 0.9, 2.37, 5.3}[std::size_t(k % 4)];
  add_scaled_copy(m, where, scale);
  return scale;
}

// prepare_input's message when the only cells overlapping others are
// `extras`: the pair (cell, other) with the smallest cell, then the
// smallest other, whose other's centroid lies strictly inside the cell.
std::string expected_overlap(const Mesh &m, const std::vector<CellId> &extras,
                             const std::string &path) {
  std::pair<CellId, CellId> best{CellId(-1), CellId(-1)};
  for (CellId e : extras) {
    const std::vector<double> ge = centroid_of(m, e);
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      if (CellId(c) == e)
        continue;
      if (strictly_inside(m, CellId(c), ge))
        best = std::min(best, {CellId(c), e});
      if (strictly_inside(m, e, centroid_of(m, CellId(c))))
        best = std::min(best, {e, CellId(c)});
    }
  }
  if (best.first == CellId(-1))
    return "no error";
  const std::string a = std::to_string(best.first), b = std::to_string(best.second);
  return path + ": tangled: cells " + a + " and " + b + " overlap (the centroid of cell " + b +
         " lies inside cell " + a + ")";
}

} // namespace

TEST_CASE("overlap: a cell laid over a graded mesh, sharing no facet with it, is found with the "
          "smallest pair",
          "[check][overlap][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const double scale = GENERATE(0.3, 2.37);
  Mesh m = graded_kuhn(dim, dim == 4 ? 2 : 4);
  REQUIRE(prepare_error(m, "t.vtu") == "no error");
  // In the fine part (x < 0.3) and in the coarse part.
  for (double x : {0.21, 0.63}) {
    Mesh bad = m;
    std::vector<double> where(std::size_t(dim), 0.47);
    where[0] = x;
    const CellId extra = add_scaled_copy(bad, where, scale);
    const std::string expected = expected_overlap(bad, {extra}, "t.vtu");
    INFO("dim " << dim << ", scale " << scale << ", x " << x << ", " << bad.num_cells()
                << " cells");
    CHECK(expected != "no error");
    CHECK(prepare_error(bad, "t.vtu") == expected);
  }
}

TEST_CASE("overlap: the same finding for 1, 2 and 3 threads, the smallest pair of several",
          "[check][overlap][threads][3d]") {
  // Large enough for several blocks of the search (8,192 cells each) and two
  // workers.
  Mesh m = generate_kuhn(3, 8);
  mark_mesh(m, Marking::Longest);
  while (m.num_cells() < 90000)
    refine_uniform(m);
  const CellId a = add_scaled_copy(m, {0.7, 0.2, 0.4}, 2.37);
  const CellId b = add_scaled_copy(m, {0.3, 0.6, 0.5}, 0.3);
  const std::string expected = expected_overlap(m, {a, b}, "t.vtu");
  REQUIRE(expected != "no error");
  INFO(m.num_cells() << " cells");
  for (int t : {1, 2, 3}) {
    set_threads(t);
    CHECK(prepare_error(m, "t.vtu") == expected);
  }
  set_threads(0);
}

TEST_CASE("overlap: the search by groups finds what each cell's own search finds, and the "
          "brute force",
          "[check][overlap][threads][2d][3d][4d]") {
  // Many groups (2,048 centroids at most each), cells laid over the fine
  // and the coarse part at several scales: small ones inside a cell, large
  // ones whose boxes pass their group's (searched on their own).
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = graded_kuhn(dim, dim == 2 ? 40 : dim == 3 ? 8 : 3);
  INFO("dim " << dim << ", " << m.num_cells() << " cells");
  REQUIRE(m.num_cells() > 3 * 2048);
  int found = 0;
  for (int k = 0; k < 12; ++k) {
    Mesh bad = m;
    const double scale = lay_cell_over(bad, k);
    const std::string expected = expected_overlap(bad, {CellId(bad.num_cells() - 1)}, "t.vtu");
    found += expected != "no error";
    INFO("case " << k << ", scale " << scale);
    for (bool own : {false, true})
      for (int t : {1, 2}) {
        testing::use_own_overlap_search(own);
        set_threads(t);
        CHECK(prepare_error(bad, "t.vtu") == expected);
      }
    testing::use_own_overlap_search(false);
    set_threads(0);
  }
  CHECK(found >= 9);
}

// ---- the overlap check's fast path (centroids_wound_once in check.cpp) ----

namespace {

// prepare_input's message and whether the ray count settled the overlap
// check (testing::overlap_fast_path_taken).
std::pair<std::string, bool> prepare_fast(const Mesh &m) {
  const std::string s = prepare_error(m, "t.vtu");
  return {s, testing::overlap_fast_path_taken()};
}

// Two copies of `m`, the second moved by `shift` along every axis.
Mesh two_copies(const Mesh &m, double shift) {
  Mesh two = m;
  const VertexId nv = VertexId(m.num_vertices());
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    std::vector<double> x(m.point(VertexId(v)), m.point(VertexId(v)) + m.dim);
    for (double &xi : x)
      xi += shift;
    add_vertex(two, x);
  }
  for (VertexId id : m.cells)
    two.cells.push_back(id + nv);
  return two;
}

} // namespace

TEST_CASE("overlap fast path: every centroid of a valid mesh counts one cell, so the search is "
          "skipped",
          "[check][overlap][2d][3d][4d]") {
  struct Case {
    std::string name;
    Mesh mesh;
  };
  std::vector<Case> cases;
  for (int dim : {2, 3, 4}) {
    cases.push_back(
        {"graded Kuhn " + std::to_string(dim) + "D", graded_kuhn(dim, dim == 4 ? 2 : 4)});
    // axis-aligned faces and rational centroids: rays skew to every axis
    cases.push_back({"Kuhn " + std::to_string(dim) + "D", generate_kuhn(dim, dim == 4 ? 3 : 6)});
    // two bodies apart (two regions of the boxes' grid, counts 1 and 0
    // between them), and one far from the origin
    cases.push_back(
        {"two Kuhn cubes " + std::to_string(dim) + "D", two_copies(generate_kuhn(dim, 2), 1.5)});
    Mesh far = generate_kuhn(dim, 3);
    for (double &x : far.coords)
      x = 1e6 + 1e-3 * x;
    cases.push_back({"Kuhn far from the origin " + std::to_string(dim) + "D", far});
  }
  for (const char *name : {"square.msh", "ball.msh", "cylinder.msh", "octant.msh"}) {
    Mesh m = read_mesh(testing::data_path(name));
    cases.push_back({name, m});
  }
  // A mesh with a hole: the Kuhn square without its centre cells.
  {
    Mesh m = generate_kuhn(2, 6);
    Mesh holed = m;
    holed.cells.clear();
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      double x = 0, y = 0;
      for (int i = 0; i < 3; ++i) {
        x += m.point(m.cell(CellId(c))[i])[0] / 3;
        y += m.point(m.cell(CellId(c))[i])[1] / 3;
      }
      if (std::abs(x - 0.5) > 0.2 || std::abs(y - 0.5) > 0.2)
        holed.cells.insert(holed.cells.end(), m.cell(CellId(c)), m.cell(CellId(c)) + 3);
    }
    cases.push_back({"square with a hole", holed});
  }
  for (int threads : {1, 2}) {
    set_threads(threads);
    for (const Case &c : cases) {
      INFO(c.name << ", " << c.mesh.num_cells() << " cells, " << threads << " threads");
      const auto [message, fast] = prepare_fast(c.mesh);
      CHECK(message == "no error");
      CHECK(fast);
    }
  }
  set_threads(0);
}

TEST_CASE("overlap fast path: where a centroid lies in two cells the count is not one, and the "
          "search names the pair",
          "[check][overlap][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  const Mesh m = graded_kuhn(dim, dim == 4 ? 2 : 4);
  // A second copy a third of the cube away (no vertex on another): the
  // centroids where both lie count 2.
  {
    const Mesh two = two_copies(m, 0.31831);
    const auto [message, fast] = prepare_fast(two);
    CHECK_THAT(message, StartsWith("t.vtu: tangled: cells "));
    CHECK_FALSE(fast);
  }
  // Cells laid over the mesh, as in the search's own tests: the search runs
  // whenever the count is not sure, and its finding is the brute force's.
  int found = 0;
  for (int k = 0; k < 8; ++k) {
    Mesh bad = m;
    const double scale = lay_cell_over(bad, k);
    const std::string expected = expected_overlap(bad, {CellId(bad.num_cells() - 1)}, "t.vtu");
    INFO("dim " << dim << ", case " << k << ", scale " << scale);
    const auto [message, fast] = prepare_fast(bad);
    CHECK(message == expected);
    if (expected != "no error") {
      ++found;
      CHECK_FALSE(fast);
    }
    // without the fast path: the same verdict and message
    testing::use_overlap_fast_path(false);
    CHECK(prepare_error(bad, "t.vtu") == expected);
    testing::use_overlap_fast_path(true);
  }
  CHECK(found >= 5);
}

TEST_CASE("overlap fast path: the angle check skips only interior faces, where the count is 1 "
          "all around, and still finds every fold",
          "[check][overlap][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  std::vector<Mesh> meshes{graded_kuhn(dim, dim == 4 ? 2 : 6)};
  if (dim != 4)
    meshes.push_back(read_mesh(testing::data_path(dim == 2 ? "square.msh" : "ball.msh")));
  for (const Mesh &m : meshes)
    for (int threads : {1, 2}) {
      set_threads(threads);
      std::vector<std::vector<VertexId>> skipped;
      testing::record_skipped_faces(&skipped);
      const auto [message, fast] = prepare_fast(m);
      testing::record_skipped_faces(nullptr);
      INFO("dim " << dim << ", " << m.num_cells() << " cells, " << threads << " threads");
      REQUIRE(message == "no error");
      REQUIRE(fast);
      // The faces (dim - 1 vertices) of the boundary facets, and all faces.
      std::set<std::vector<VertexId>> boundary, all;
      std::map<std::vector<VertexId>, int> facets;
      auto without = [](const std::vector<VertexId> &x, std::size_t i) {
        std::vector<VertexId> y;
        for (std::size_t k = 0; k < x.size(); ++k)
          if (k != i)
            y.push_back(x[k]);
        return y;
      };
      for (std::size_t c = 0; c < m.num_cells(); ++c) {
        std::vector<VertexId> x(m.cell(CellId(c)), m.cell(CellId(c)) + dim + 1);
        std::sort(x.begin(), x.end());
        for (std::size_t i = 0; i < x.size(); ++i) {
          const std::vector<VertexId> f = without(x, i);
          ++facets[f];
          for (std::size_t j = 0; j < f.size(); ++j)
            all.insert(without(f, j));
        }
      }
      for (const auto &[f, count] : facets)
        if (count == 1)
          for (std::size_t j = 0; j < f.size(); ++j)
            boundary.insert(without(f, j));
      std::set<std::vector<VertexId>> seen;
      for (const auto &g : skipped) {
        CHECK(all.count(g) == 1);
        CHECK(boundary.count(g) == 0);
        CHECK(seen.insert(g).second);
      }
      // some interior faces, not all faces
      CHECK(!skipped.empty());
      CHECK(skipped.size() < all.size() - boundary.size());
    }
  set_threads(0);
}

TEST_CASE("input facts: validation's invariants and interior facets are those measured apart "
          "(2D, 3D, 4D, 1-3 threads)",
          "[check][threads][2d][3d][4d]") {
  const int dim = GENERATE(2, 3, 4);
  Mesh m = graded_kuhn(dim, dim == 4 ? 2 : 4);
  Mesh plain = m;
  prepare_input(plain, "t.vtu");
  const Invariants want = measure_invariants(plain);
  std::vector<std::array<int, 4>> walked;
  for_each_interior_facet(plain, [&](CellId a, int i, CellId b, int j) {
    walked.push_back({int(a), i, int(b), j});
    return true;
  });
  for (int t : {1, 2, 3}) {
    INFO("dim " << dim << ", threads " << t);
    set_threads(t);
    Mesh copy = m;
    InputFacts facts;
    facts.want_interior = true;
    prepare_input(copy, "t.vtu", {}, &facts);
    CHECK(facts.invariants.volume == want.volume);
    CHECK(facts.invariants.boundary_measure == want.boundary_measure);
    CHECK(facts.invariants.boundary_facets == want.boundary_facets);
    CHECK(facts.invariants.euler == want.euler);
    std::vector<std::array<int, 4>> recorded;
    for_each_interior_facet(copy, facts.interior, [&](CellId a, int i, CellId b, int j) {
      recorded.push_back({int(a), i, int(b), j});
      return true;
    });
    CHECK(recorded == walked);
  }
  set_threads(0);
}

TEST_CASE("facet walk: the narrow packing (8 bytes a facet) gives the wide one's facts, findings "
          "and messages (3D)",
          "[check][3d]") {
  std::vector<Mesh> meshes{graded_kuhn(3, 4), read_mesh(testing::data_path("ball.msh"))};
  // Broken copies of a Kuhn mesh, one vertex id changed in each: overlaps,
  // facets of three cells, flat cells.
  const Mesh kuhn = generate_kuhn(3, 3);
  for (std::size_t c = 0; c < kuhn.num_cells(); c += 7) {
    Mesh m = kuhn;
    m.cell(CellId(c))[c % 4] = VertexId((c * 7 + 3) % kuhn.num_vertices());
    meshes.push_back(m);
  }
  struct Seen {
    std::string message;
    bool fast = false;
    Invariants facts, measured;
    InteriorFacets interior;
    std::string check;
  };
  auto run = [](const Mesh &m, bool narrow) {
    testing::use_narrow_facet_walk(narrow);
    Seen s;
    Mesh copy = m;
    InputFacts facts;
    facts.want_interior = true;
    try {
      prepare_input(copy, "t.vtu", {}, &facts);
      s.message = "no error";
    } catch (const InputError &e) {
      s.message = e.what();
    }
    s.fast = testing::overlap_fast_path_taken();
    s.facts = facts.invariants;
    s.interior = facts.interior;
    s.measured = measure_invariants(m);
    s.check = check_conformity(m).failure;
    testing::use_narrow_facet_walk(true);
    return s;
  };
  int errors = 0;
  for (std::size_t chunk : {std::size_t(0), std::size_t(1) << 12}) // several chunks too
    for (const Mesh &m : meshes) {
      testing::set_walk_chunk_bytes(chunk);
      const Seen narrow = run(m, true), wide = run(m, false);
      testing::set_walk_chunk_bytes(0);
      INFO(m.num_cells() << " cells, chunk budget " << chunk << ": " << wide.message);
      CHECK(narrow.message == wide.message);
      CHECK(narrow.fast == wide.fast);
      CHECK(narrow.facts.volume == wide.facts.volume);
      CHECK(narrow.facts.boundary_measure == wide.facts.boundary_measure);
      CHECK(narrow.facts.boundary_facets == wide.facts.boundary_facets);
      CHECK(narrow.facts.euler == wide.facts.euler);
      CHECK(narrow.interior == wide.interior);
      CHECK(narrow.measured.boundary_measure == wide.measured.boundary_measure);
      CHECK(narrow.measured.boundary_facets == wide.measured.boundary_facets);
      CHECK(narrow.measured.euler == wide.measured.euler);
      CHECK(narrow.check == wide.check);
      errors += wide.message != "no error";
    }
  CHECK(errors >= 10);
}

TEST_CASE("final check: cell facts taken with the quality give the same quality and verdicts, "
          "and are used only for the mesh they describe",
          "[check][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    // More than two 16,384-cell blocks, so block order matters.
    Mesh m = generate_kuhn(dim, dim == 2 ? 40 : dim == 3 ? 12 : 5);
    mark_mesh(m, Marking::Index);
    const Invariants original = measure_invariants(m, false);
    while (m.num_cells() < 40000)
      refine_uniform(m);
    refine(m, {0, 1, 2, 3});
    const int n = dim + 1;
    const std::size_t nc = m.num_cells(), nv = m.num_vertices();
    std::vector<std::pair<std::string, Mesh>> cases;
    cases.emplace_back("honest", m);
    Mesh moved = m; // a fold and a hanging node, found by the facet walk
    moved.cells[std::size_t(n) * (nc / 2) + 1] = moved.cells[std::size_t(n) * (nc / 2 + 1) + 2];
    cases.emplace_back("moved", std::move(moved));
    Mesh flat = m; // a cell squashed onto its first vertex's neighbour: degenerate
    for (int d = 0; d < dim; ++d)
      flat.coords[std::size_t(dim) * flat.cell(CellId(nc - 7))[1] + std::size_t(d)] =
          flat.point(flat.cell(CellId(nc - 7))[0])[d];
    cases.emplace_back("flat", std::move(flat));
    Mesh out = m; // an id out of range, in the second block
    out.cells[std::size_t(n) * 20000 + 2] = VertexId(nv + 1);
    cases.emplace_back("out of range", std::move(out));
    for (const auto &[what, mesh] : cases) {
      INFO("dim " << dim << ", " << what);
      CellFacts facts;
      const QualitySummary q = quality_with_cell_facts(mesh, facts);
      REQUIRE(facts.describe(mesh));
      REQUIRE(facts.signs.size() == mesh.num_cells());
      if (what != "out of range") { // whose quality is undefined
        const QualitySummary plain = quality_summary(mesh);
        CHECK(q.min == plain.min); // bit for bit
        CHECK(q.max == plain.max);
        CHECK(q.mean == plain.mean);
      }
      const CheckResult alone = check_refined(mesh, original);
      CHECK(check_refined(mesh, original, &facts).failure == alone.failure);
      CHECK((what == "honest") == alone.ok);
    }
    // Facts are believed for the mesh they describe (a forged volume is
    // reported) and ignored for any other (another mesh of the same sizes,
    // or this one after a cell was added).
    CellFacts facts;
    quality_with_cell_facts(m, facts);
    CellFacts forged = facts;
    forged.volume *= 1.5;
    INFO("dim " << dim);
    CHECK_THAT(check_refined(m, original, &forged).failure, StartsWith("volume changed"));
    const Mesh &moved_mesh = cases[1].second;
    CHECK(check_refined(moved_mesh, original, &facts).failure ==
          check_refined(moved_mesh, original).failure);
    Mesh grown = m;
    grown.cells.insert(grown.cells.end(), m.cells.begin(), m.cells.begin() + n);
    facts.cells = grown.cells.data();
    facts.coords = grown.coords.data();
    CHECK(!facts.describe(grown));
    CHECK(check_refined(grown, original, &facts).failure == check_refined(grown, original).failure);
    CHECK(!check_refined(grown, original).ok);
  }
}

TEST_CASE("angle check: the quick atan2 stays within 2e-5 of std::atan2", "[check]") {
  // The angle check decides an interior face by the rough sum of its
  // wedges when that is near one turn; the shortcut is exact as long as
  // each rough angle is within 2e-5 (a face has fewer than 10,000 cells).
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double worst = 0;
  auto probe = [&](double y, double x) {
    worst = std::max(worst, std::abs(testing::rough_angle(y, x) - std::atan2(y, x)));
  };
  for (int i = 0; i < 200000; ++i) {
    const double scale = std::ldexp(1.0, int(unit(rng) * 60));
    probe(std::abs(unit(rng)) * scale, unit(rng) * scale);
  }
  for (double y : {0.0, 1e-300, 1.0, 1e300})
    for (double x : {-1e300, -1.0, -1e-300, 0.0, 1e-300, 1.0, 1e300})
      if (y != 0 || x != 0)
        probe(y, x);
  CHECK(worst < 2e-5);
  CHECK(std::isnan(testing::rough_angle(0.0, 0.0))); // the exact path takes it
}

TEST_CASE("angle check (4D): the triangles found from the vertex stars give the walk's faces "
          "count, skipped faces and findings",
          "[check][4d]") {
  // Valid meshes, and Kuhn meshes with one vertex id changed (tangled,
  // flat, non-manifold; some found by the angle sums alone).
  std::vector<Mesh> meshes{graded_kuhn(4, 2), generate_kuhn(4, 2)};
  const Mesh kuhn = generate_kuhn(4, 2);
  for (std::size_t c = 0; c < kuhn.num_cells(); c += 23)
    for (int i = 0; i < 5; ++i)
      for (VertexId v = VertexId(c % 7); v < kuhn.num_vertices(); v += 9) {
        const VertexId *cell = kuhn.cell(CellId(c));
        if (std::find(cell, cell + 5, v) != cell + 5)
          continue;
        Mesh m = kuhn;
        m.cell(CellId(c))[i] = v;
        meshes.push_back(m);
      }
  struct Seen {
    std::string message;
    long long euler = 0;
    std::vector<std::vector<VertexId>> skipped;
  };
  auto run = [](const Mesh &m, bool walk) {
    testing::use_walk_fold4(walk);
    Seen s;
    testing::record_skipped_faces(&s.skipped);
    Mesh copy = m;
    InputFacts facts;
    try {
      prepare_input(copy, "k.vtu", {}, &facts);
      s.message = "no error";
      s.euler = facts.invariants.euler;
    } catch (const InputError &e) {
      s.message = e.what();
    }
    testing::record_skipped_faces(nullptr);
    testing::use_walk_fold4(false);
    std::sort(s.skipped.begin(), s.skipped.end()); // threads record in any order
    return s;
  };
  int by_angles = 0, valid = 0;
  for (int threads : {1, 2}) {
    set_threads(threads);
    for (const Mesh &m : meshes) {
      const Seen stars = run(m, false), walk = run(m, true);
      INFO(threads << " threads: " << walk.message);
      CHECK(stars.message == walk.message);
      CHECK(stars.euler == walk.euler);
      CHECK(stars.skipped == walk.skipped);
      by_angles += Contains(" cells around ").match(walk.message);
      valid += walk.message == "no error";
    }
  }
  set_threads(0);
  CHECK(by_angles >= 4);
  CHECK(valid >= 4);
}
