// 4D: Stage 1 then Maubach (ALGORITHMS.md §4, seed 000).
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

using namespace bisect;

namespace {

// Two pentatopes {0,1,2,3,4} and {1,2,3,4,5} sharing the tetrahedron {1,2,3,4}.
Mesh two_pentatopes() {
  Mesh m;
  m.dim = 4;
  m.coords = {0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.9, 0.8, 0.7, 0.6};
  // vertex 0 is the origin; 5 lies beyond the facet {1,2,3,4}
  m.cells = {0, 1, 2, 3, 4, 1, 2, 3, 4, 5};
  prepare_input(m, "two");
  return m;
}

} // namespace

TEST_CASE("4D: skipping Stage 1 with the index order is not conformal; Stage 1 is",
          "[refine][4d]") {
  Mesh with_stage1 = two_pentatopes();
  mark_mesh(with_stage1, Marking::Index);
  Invariants inv = measure_invariants(with_stage1);
  for (int it = 0; it < 3; ++it)
    refine_uniform(with_stage1);
  REQUIRE_CONFORMING(with_stage1, inv);

  // Without Stage 1 every pentatope is (a, c, b, e, d)_2 for sorted ids a<b<c<d<e.
  Mesh skipped = two_pentatopes();
  mark_mesh(skipped, Marking::Index);
  for (std::size_t c = 0; c < skipped.num_cells(); ++c) {
    VertexId *x = skipped.cell(CellId(c));
    std::sort(x, x + 5);
    VertexId a = x[0], b = x[1], cc = x[2], d = x[3], e = x[4];
    x[0] = a, x[1] = cc, x[2] = b, x[3] = e, x[4] = d;
    skipped.stage[c] = Stage::Maubach;
    skipped.tag[c] = 2;
  }
  for (int it = 0; it < 3; ++it)
    refine_uniform(skipped);
  CheckResult r = check_conformity(skipped, &inv);
  INFO(r.failure);
  REQUIRE_FALSE(r.ok);
}

TEST_CASE("4D: local refinement of renumbered Kuhn hypercubes stays conforming", "[refine][4d]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    for (Marking mk : {Marking::Index, Marking::Longest, Marking::Sorted}) {
      Mesh m = testing::renumbered(generate_kuhn(4, 2), seed);
      mark_mesh(m, mk);
      Invariants inv = measure_invariants(m);
      auto region =
          parse_region(R"({"type":"sphere","center":[0.3,0.4,0.5,0.45],"radius":0.4})", 4, "t");
      for (int it = 1; it <= 6; ++it) {
        refine(m, select_cells(m, *region));
        INFO("seed " << seed << " marking " << marking_name(mk) << " iteration " << it);
        REQUIRE_CONFORMING(m, inv);
      }
    }
  }
}

TEST_CASE("4D: Stage 1 leaves every grandchild a Maubach tuple with tag 2", "[refine][4d]") {
  Mesh m = generate_simplex(4, SimplexShape::Random, 9);
  mark_mesh(m, Marking::Longest);
  REQUIRE(m.stage[0] == Stage::Opposite);
  refine_uniform(m);
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    REQUIRE(m.stage[c] == Stage::Opposite);
    REQUIRE(m.tag[c] == 1);
  }
  refine_uniform(m);
  // Two Stage 1 generations: every cell that has taken both is
  // (alpha, gamma, beta, u, v)_2 with v = 5 the first new vertex and u newer;
  // closure may bisect some of them once more (the two children need not
  // agree on a shared edge), leaving Maubach children with tag 1.
  std::size_t grandchildren = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    REQUIRE(m.stage[c] == Stage::Maubach);
    const VertexId *x = m.cell(CellId(c));
    if (m.tag[c] != 2)
      continue;
    ++grandchildren;
    REQUIRE(x[4] == 5);
    REQUIRE(x[3] > x[4]);
  }
  REQUIRE(grandchildren >= 2);
}

TEST_CASE("4D uniform: min and max quality cycle with period 4; classes within 1536",
          "[refine][4d][quality]") {
  for (SimplexShape shape : {SimplexShape::Equilateral, SimplexShape::Random}) {
    for (Marking mk : {Marking::Longest, Marking::Index, Marking::Sorted}) {
      Mesh m = generate_simplex(4, shape, 2);
      mark_mesh(m, mk);
      std::vector<double> qmin, qmax;
      Mesh all = m;
      const int iterations = 18;
      for (int it = 1; it <= iterations; ++it) {
        refine_uniform(m);
        QualitySummary q = quality_summary(m);
        qmin.push_back(q.min);
        qmax.push_back(q.max);
        if (it <= 14) { // classes over the first 14 generations (32k cells)
          all.coords = m.coords;
          all.cells.insert(all.cells.end(), m.cells.begin(), m.cells.end());
        }
      }
      all.stage.clear();
      std::size_t classes = count_similarity_classes(all);
      INFO("shape " << int(shape) << " marking " << marking_name(mk) << " classes " << classes);
      REQUIRE(classes <= (mk == Marking::Sorted ? 384u : 1536u));
      // Stage 1 takes two bisections, then Maubach's cycle of length 4, once
      // every class has appeared (iteration 10 onwards for a random pentatope).
      for (int k = 10; k + 4 < iterations; ++k) {
        REQUIRE(qmin[k] == Approx(qmin[k + 4]).epsilon(1e-9));
        REQUIRE(qmax[k] == Approx(qmax[k + 4]).epsilon(1e-9));
      }
    }
  }
}
