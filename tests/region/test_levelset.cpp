// Tests for levelset.cpp: the sampled zero-set test against the exact
// regions, the Hessian and its indicator, refinement with a levelset region,
// singular formulas, and the spec errors.
#include "region/levelset.hpp"

#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace bisect;

namespace {

std::unique_ptr<Region> spec(const std::string &text, int dim) {
  return parse_region(text, dim, "test.json");
}

std::vector<double> cell_points(const Mesh &m, CellId c) {
  std::vector<double> v;
  for (int i = 0; i <= m.dim; ++i)
    v.insert(v.end(), m.point(m.cell(c)[i]), m.point(m.cell(c)[i]) + m.dim);
  return v;
}

bool is_subset(const std::vector<CellId> &a, const std::vector<CellId> &b) {
  return std::includes(b.begin(), b.end(), a.begin(), a.end());
}

// The error parse_region throws for `text`, or "" when it parses.
std::string error_of(const std::string &text, int dim) {
  try {
    spec(text, dim);
  } catch (const InputError &e) {
    return e.what();
  }
  return "";
}

std::string samples(int k) {
  return std::to_string(k);
}

} // namespace

TEST_CASE("levelset: a plane selects exactly the cells the exact plane test selects",
          "[region][levelset]") {
  // The plane's cells: those touching both closed halfspaces (an intersection
  // of two halfspaces is exact for a plane, the simplex being convex).
  for (int dim : {2, 3}) {
    const Mesh m = testing::perturbed_inside_box(generate_kuhn(dim, 6), 0.03, 5);
    const std::string expr = dim == 2 ? "x + 2*y" : "x + 2*y - z";
    const std::string n = dim == 2 ? "1, 2" : "1, 2, -1", minus = dim == 2 ? "-1, -2" : "-1, -2, 1";
    for (const double offset : {0.3, 0.5, 1.1}) {
      const std::string o = std::to_string(offset), mo = std::to_string(-offset);
      auto exact = spec(R"({"type":"intersection","regions":[{"type":"halfspace","normal":[)" + n +
                            "],\"offset\":" + o + R"(},{"type":"halfspace","normal":[)" + minus +
                            "],\"offset\":" + mo + "}]}",
                        dim);
      const std::vector<CellId> want = select_cells(m, *exact);
      REQUIRE(!want.empty());
      for (int k : {1, 2, 3}) {
        auto level = spec(R"({"type":"levelset","expression":")" + expr + "\",\"value\":" + o +
                              ",\"samples\":" + samples(k) + "}",
                          dim);
        INFO("dim " << dim << " offset " << offset << " samples " << k);
        CHECK(select_cells(m, *level) == want);
      }
    }
  }
}

TEST_CASE("levelset: a plane through vertices selects the cells touching it",
          "[region][levelset]") {
  // x = 1/2 on the Kuhn grid passes through vertices exactly (no rounding).
  const Mesh m = generate_kuhn(3, 4);
  auto level = spec(R"({"type":"levelset","expression":"x","value":0.5})", 3);
  auto exact = spec(
      R"({"type":"intersection","regions":[{"type":"halfspace","normal":[1,0,0],"offset":0.5},)"
      R"({"type":"halfspace","normal":[-1,0,0],"offset":-0.5}]})",
      3);
  const std::vector<CellId> got = select_cells(m, *level);
  CHECK(got == select_cells(m, *exact));
  // Every cell with a vertex on the plane: the closed simplex touches it.
  std::size_t on_plane = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    bool touch = false;
    for (int i = 0; i < 4; ++i)
      touch |= m.point(m.cell(CellId(c))[i])[0] == 0.5;
    on_plane += touch;
  }
  CHECK(got.size() == on_plane);
}

TEST_CASE("levelset: a sphere's selection lies inside the exact one and grows with the samples",
          "[region][levelset]") {
  const Mesh m = testing::perturbed_inside_box(generate_kuhn(3, 6), 0.03, 11);
  auto exact = spec(R"({"type":"sphere","center":[0.45,0.52,0.48],"radius":0.31})", 3);
  const std::vector<CellId> want = select_cells(m, *exact);
  std::vector<CellId> previous;
  for (int k : {1, 2, 4, 8}) {
    auto level = spec(R"({"type":"levelset","expression":"(x-0.45)^2+(y-0.52)^2+(z-0.48)^2",)"
                      R"("value":0.0961,"samples":)" +
                          samples(k) + "}",
                      3);
    const std::vector<CellId> got = select_cells(m, *level);
    INFO("samples " << k << ": " << got.size() << " of " << want.size());
    CHECK(is_subset(got, want));     // never a false "yes"
    CHECK(is_subset(previous, got)); // lattice(k/2) is part of lattice(k)
    previous = got;
    // What is missed: every sample on one side, so in particular the vertices.
    for (CellId c : want) {
      if (std::binary_search(got.begin(), got.end(), c))
        continue;
      const std::vector<double> v = cell_points(m, c);
      int inside = 0;
      for (int i = 0; i < 4; ++i) {
        const double *p = v.data() + 3 * i;
        inside += (p[0] - 0.45) * (p[0] - 0.45) + (p[1] - 0.52) * (p[1] - 0.52) +
                      (p[2] - 0.48) * (p[2] - 0.48) <=
                  0.0961;
      }
      CHECK((inside == 0 || inside == 4));
    }
    if (k == 1)
      CHECK(got.size() < want.size()); // vertices alone miss grazing cells here
    if (k == 8)
      CHECK(got == want); // enough samples for this mesh: nothing missed
  }
}

TEST_CASE("levelset: solid selects the cells touching the sublevel set", "[region][levelset]") {
  const Mesh m = testing::perturbed_inside_box(generate_kuhn(2, 8), 0.02, 3);
  auto ball = spec(R"({"type":"sphere","center":[0.5,0.5],"radius":0.3,"solid":true})", 2);
  auto level = spec(R"({"type":"levelset","expression":"(x-0.5)^2+(y-0.5)^2","value":0.09,)"
                    R"("solid":true,"samples":8})",
                    2);
  const std::vector<CellId> want = select_cells(m, *ball), got = select_cells(m, *level);
  CHECK(is_subset(got, want));
  CHECK(got.size() + 4 >= want.size()); // only cells the circle grazes may be missed
}

TEST_CASE("levelset: the Hessian by central differences is exact for quadratics", "[levelset]") {
  // f = 3x^2 - 2xy + 5yz + z^2 + x - 7 (3D) and with + 4t^2 - tx (4D).
  const std::vector<std::vector<double>> want3 = {{6, -2, 0}, {-2, 0, 5}, {0, 5, 2}};
  const std::vector<std::vector<double>> want4 = {
      {6, -2, 0, -1}, {-2, 0, 5, 0}, {0, 5, 2, 0}, {-1, 0, 0, 8}};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int dim : {3, 4}) {
    const std::vector<std::string> vars = dim == 3 ? std::vector<std::string>{"x", "y", "z"}
                                                   : std::vector<std::string>{"x", "y", "z", "t"};
    const LevelsetFunction f(dim == 3 ? "3*x^2 - 2*x*y + 5*y*z + z^2 + x - 7"
                                      : "3*x^2 - 2*x*y + 5*y*z + z^2 + x - 7 + 4*t^2 - t*x",
                             vars, {});
    const auto &want = dim == 3 ? want3 : want4;
    for (int trial = 0; trial < 20; ++trial) {
      double x[4], H[16];
      for (double &c : x)
        c = u(rng);
      for (double step : {1e-3, 1e-2, 0.5}) {
        f.hessian(x, step, H);
        for (int k = 0; k < dim; ++k)
          for (int l = 0; l < dim; ++l) {
            INFO("dim " << dim << " step " << step << " H[" << k << "][" << l << "]");
            CHECK(H[k * dim + l] == Approx(want[k][l]).margin(1e-6));
          }
      }
    }
  }
}

TEST_CASE("levelset: the indicator of a quadratic is sum |h_i^T A h_i|", "[levelset]") {
  const LevelsetFunction f("x^2 + 3*x*y - 2*y^2", {"x", "y"}, {});
  const double A[2][2] = {{2, 3}, {3, -4}};
  const std::vector<double> v = {0.1, 0.2, 1.3, -0.4, 0.5, 0.9};
  const double c[2] = {(0.1 + 1.3 + 0.5) / 3, (0.2 - 0.4 + 0.9) / 3};
  double want = 0;
  for (int i = 0; i < 3; ++i) {
    const double h[2] = {v[2 * i] - c[0], v[2 * i + 1] - c[1]};
    want += std::abs(h[0] * (A[0][0] * h[0] + A[0][1] * h[1]) +
                     h[1] * (A[1][0] * h[0] + A[1][1] * h[1]));
  }
  CHECK(hessian_indicator(f, v.data(), 2) == Approx(want).epsilon(1e-6));
  // An affine function does not curve.
  CHECK(hessian_indicator(LevelsetFunction("3*x - y", {"x", "y"}, {}), v.data(), 2) ==
        Approx(0).margin(1e-6));
  // A non-quadratic f: the directional differences agree with the quadratic
  // forms of the full difference Hessian.
  const LevelsetFunction g("-1/sqrt((x-0.5)^2+(y-0.125)^2+t^2) + sin(3*x)*exp(y*t)",
                           {"x", "y", "t"}, {});
  const std::vector<double> tet = {0.9, 0.6, 0.1, 1.0, 0.7, 0.15, 0.95, 0.8, 0.05, 0.85, 0.65, 0.3};
  double longest = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      longest =
          std::max(longest, std::hypot(tet[3 * i] - tet[3 * j], tet[3 * i + 1] - tet[3 * j + 1],
                                       tet[3 * i + 2] - tet[3 * j + 2]));
  double full = 0;
  for (int i = 0; i < 4; ++i) {
    double H[9], h[3];
    g.hessian(tet.data() + 3 * i, kHessianStep * longest, H);
    for (int k = 0; k < 3; ++k)
      h[k] = tet[3 * i + k] - (tet[k] + tet[3 + k] + tet[6 + k] + tet[9 + k]) / 4;
    double q = 0;
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        q += h[k] * H[3 * k + l] * h[l];
    full += std::abs(q);
  }
  CHECK(full > 0.1);
  CHECK(hessian_indicator(g, tet.data(), 3) == Approx(full).epsilon(1e-4));
}

TEST_CASE("levelset indicator: keeps round(fraction n) cells, those with the largest e",
          "[region][levelset]") {
  const Mesh m = testing::perturbed_inside_box(generate_kuhn(3, 6), 0.03, 2);
  const std::string body =
      R"("type":"levelset","variables":["x","y","t"],"constants":{"v":0.375},)"
      R"~("expression":"-1/sqrt((x-0.5)^2+(y-0.125-v*t)^2) - 1/sqrt((x-0.5)^2+(y-0.875+v*t)^2)",)~"
      R"("value":-4)";
  const std::vector<CellId> all = select_cells(m, *spec("{" + body + "}", 3));
  REQUIRE(all.size() > 50);
  const LevelsetFunction f("-1/sqrt((x-0.5)^2+(y-0.125-v*t)^2) - 1/sqrt((x-0.5)^2+(y-0.875+v*t)^2)",
                           {"x", "y", "t"}, {{"v", 0.375}});
  for (const std::string text : {"0.1", "0.25", "0.5", "1e-9", "1"}) {
    const double fraction = std::stod(text);
    auto region =
        spec("{" + body + R"(,"indicator":{"type":"hessian","fraction":)" + text + "}}", 3);
    const std::vector<CellId> kept = select_cells(m, *region);
    INFO("fraction " << fraction);
    const std::size_t want =
        std::max<std::size_t>(1, std::size_t(std::llround(fraction * double(all.size()))));
    CHECK(kept.size() == want);
    CHECK(std::is_sorted(kept.begin(), kept.end()));
    CHECK(is_subset(kept, all));
    double least_kept = INFINITY, most_dropped = -INFINITY;
    for (CellId c : all) {
      const double e = hessian_indicator(f, cell_points(m, c).data(), 3);
      if (std::binary_search(kept.begin(), kept.end(), c))
        least_kept = std::min(least_kept, e);
      else
        most_dropped = std::max(most_dropped, e);
    }
    CHECK(least_kept >= most_dropped);
  }
  // No cell selected: nothing to keep, and no crash.
  auto none = spec(R"({"type":"levelset","expression":"x","value":5,)"
                   R"("indicator":{"type":"hessian","fraction":0.1}})",
                   3);
  CHECK(select_cells(m, *none).empty());
}

TEST_CASE("levelset: singular formulas do not crash and keep their signs", "[region][levelset]") {
  const Mesh m = generate_kuhn(2, 8, -1.0, 1.0); // a vertex at the origin
  // -1/r is -inf at the origin: the cells around it see -inf and r = 1/4 values.
  auto pole =
      spec(R"~({"type":"levelset","expression":"-1/sqrt(x^2+y^2)","value":-10,"samples":1})~", 2);
  const std::vector<CellId> got = select_cells(m, *pole);
  std::size_t at_origin = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    for (int i = 0; i < 3; ++i)
      at_origin += m.point(m.cell(CellId(c))[i])[0] == 0 && m.point(m.cell(CellId(c))[i])[1] == 0;
  CHECK(at_origin > 0);
  CHECK(got.size() == at_origin);
  // The indicator ranks the cells at the pole first (e = +inf).
  auto ranked =
      spec(R"~({"type":"levelset","expression":"-1/sqrt(x^2+y^2)","value":-3.5,"samples":1,)~"
           R"("indicator":{"type":"hessian","fraction":0.01}})",
           2);
  const std::vector<CellId> top = select_cells(m, *ranked);
  REQUIRE(top.size() == 1);
  const LevelsetFunction f("-1/sqrt(x^2+y^2)", {"x", "y"}, {});
  CHECK(std::isinf(hessian_indicator(f, cell_points(m, top[0]).data(), 2)));
  // NaN (sqrt of a negative) has no sign: cells with x < 0 only are never selected.
  auto half = spec(R"({"type":"levelset","expression":"sqrt(x) - 0.6","samples":3})", 2);
  for (CellId c : select_cells(m, *half)) {
    double xmax = -1;
    for (int i = 0; i < 3; ++i)
      xmax = std::max(xmax, m.point(m.cell(c)[i])[0]);
    CHECK(xmax >= 0.36);
  }
}

TEST_CASE("levelset: refinement around a moving iso-surface stays conforming",
          "[refine][levelset][3d]") {
  for (Marking mk : {Marking::Index, Marking::Longest}) {
    Mesh m = testing::renumbered(generate_kuhn(3, 3), 4);
    mark_mesh(m, mk);
    const Invariants inv = measure_invariants(m);
    auto region = spec(
        R"({"type":"levelset","variables":["x","y","t"],"constants":{"v":0.375},)"
        R"~("expression":"-1/sqrt((x-0.5)^2+(y-0.125-v*t)^2) - 1/sqrt((x-0.5)^2+(y-0.875+v*t)^2)",)~"
        R"("value":-6,"indicator":{"type":"hessian","fraction":0.2}})",
        3);
    std::size_t cells = m.num_cells();
    for (int it = 1; it <= 8; ++it) {
      const std::vector<CellId> sel = select_cells(m, *region);
      REQUIRE(!sel.empty());
      refine(m, sel);
      INFO("marking " << marking_name(mk) << " iteration " << it);
      REQUIRE_CONFORMING(m, inv);
      CHECK(m.num_cells() > cells);
      cells = m.num_cells();
    }
  }
  // 2D and 4D (default variables x, y and x, y, z, t).
  for (int dim : {2, 4}) {
    Mesh m = generate_kuhn(dim, 2);
    mark_mesh(m, Marking::Longest);
    const Invariants inv = measure_invariants(m);
    auto region = spec(dim == 2 ? R"({"type":"levelset","expression":"x^2+y^2","value":0.5})"
                                : R"({"type":"levelset","expression":"x^2+y^2+z^2-t","value":0.2,)"
                                  R"("indicator":{"type":"hessian","fraction":0.3}})",
                       dim);
    for (int it = 1; it <= (dim == 2 ? 8 : 4); ++it) {
      refine(m, select_cells(m, *region));
      INFO("dim " << dim << " iteration " << it);
      REQUIRE_CONFORMING(m, inv);
    }
  }
}

TEST_CASE("levelset: spec errors are one line naming the file and the problem",
          "[region][levelset]") {
  const auto one_line = [](const std::string &e) { return e.find('\n') == std::string::npos; };
  struct Case {
    std::string text;
    int dim;
    std::string want;
  };
  const std::vector<Case> cases = {
      {R"({"type":"levelset","expression":"x+"})", 2,
       R"(test.json: levelset: "expression": Unexpected end of expression at position 3 in "x+")"},
      {R"({"type":"levelset","expression":"(x"})", 2, "Missing parenthesis"},
      {R"({"type":"levelset","expression":"x*z"})", 2,
       R"(test.json: levelset: "expression": unknown variable "z" in "x*z" (variables: x, y; constants: none))"},
      {R"({"type":"levelset","expression":"x*t"})", 3, R"(unknown variable "t")"},
      {R"~({"type":"levelset","expression":"foo(x)"})~", 2, R"(unknown function "foo")"},
      {R"({"type":"levelset","expression":"x","variables":["x","y","t"]})", 2,
       R"(test.json: levelset: "variables" has 3 names, the mesh is 2D)"},
      {R"({"type":"levelset","expression":"x","variables":["x","y"]})", 3,
       R"("variables" has 2 names, the mesh is 3D)"},
      {R"({"type":"levelset","value":1})", 2, R"(test.json: levelset: missing "expression")"},
      {R"({"type":"levelset","expression":3})", 2, R"("expression" must be a string)"},
      {R"({"type":"levelset","expression":""})", 2, "Expression is empty"},
      {R"({"type":"levelset","expression":"x=1"})", 2, "assignments (=) are not allowed"},
      {R"({"type":"levelset","expression":"x,y"})", 2, "gives 2 values"},
      {R"({"type":"levelset","expression":"x","value":"a"})", 2,
       R"("value" must be a finite number)"},
      {R"({"type":"levelset","expression":"x","variables":["x","x"]})", 2,
       R"("x" is listed twice)"},
      {R"({"type":"levelset","expression":"x","variables":["x","2y"]})", 2,
       R"("2y" is not a name)"},
      {R"({"type":"levelset","expression":"x","constants":{"y":1}})", 2,
       R"("y" is also a variable)"},
      {R"({"type":"levelset","expression":"x","constants":{"a":"b"}})", 2,
       R"("a" must be a finite number)"},
      {R"({"type":"levelset","expression":"x","samples":0})", 2,
       R"("samples" must be a whole number from 1 to 16)"},
      {R"({"type":"levelset","expression":"x","samples":2.5})", 2,
       R"("samples" must be a whole number)"},
      {R"({"type":"levelset","expression":"x","bogus":1})", 2, R"(unknown field "bogus")"},
      {R"({"type":"levelset","expression":"x","indicator":{"type":"hessian"}})", 2,
       R"(levelset: indicator: missing "fraction")"},
      {R"({"type":"levelset","expression":"x","indicator":{"type":"hessian","fraction":0}})", 2,
       R"("fraction" must be in (0, 1])"},
      {R"({"type":"levelset","expression":"x","indicator":{"type":"grad","fraction":0.1}})", 2,
       R"(unknown indicator type "grad")"},
      {R"({"type":"levelset","expression":"x","indicator":{"type":"hessian","fraction":0.1,"expression":"q"}})",
       2, R"(indicator: "expression": unknown variable "q")"},
      {R"({"type":"union","regions":[{"type":"levelset","expression":"x","indicator":{"type":"hessian","fraction":0.1}}]})",
       2,
       R"(regions[0]: levelset: an "indicator" is only allowed on a levelset region at the top)"},
  };
  for (const Case &c : cases) {
    INFO(c.text);
    const std::string e = error_of(c.text, c.dim);
    CHECK_THAT(e, Catch::Matchers::StartsWith("test.json: "));
    CHECK_THAT(e, Catch::Matchers::Contains(c.want));
    CHECK(one_line(e));
  }
  // An expression with a newline is quoted on one line.
  CHECK(one_line(error_of("{\"type\":\"levelset\",\"expression\":\"x\\n+\"}", 2)));
}

TEST_CASE("levelset: the bundled two-body spec is a 2D+t (3D) region", "[region][levelset][io]") {
  const std::string path = testing::data_path("regions/two-body.json");
  CHECK(read_region(path, 3) != nullptr);
  CHECK_THROWS_WITH(read_region(path, 2),
                    Catch::Matchers::StartsWith(path + ": levelset: \"variables\" has 3 names"));
  CHECK_THROWS_WITH(read_region(path, 4),
                    Catch::Matchers::StartsWith(path + ": levelset: \"variables\" has 3 names"));
}

TEST_CASE("levelset: the barycentric lattice has C(dim+k, dim) points, vertices first",
          "[levelset]") {
  for (int dim = 2; dim <= 4; ++dim)
    for (int k = 1; k <= 5; ++k) {
      const std::vector<double> w = barycentric_lattice(dim, k);
      long long want = 1;
      for (int i = 1; i <= dim; ++i)
        want = want * (k + i) / i;
      REQUIRE(w.size() == std::size_t(want * (dim + 1)));
      for (int i = 0; i <= dim; ++i)
        for (int j = 0; j <= dim; ++j)
          CHECK(w[i * (dim + 1) + j] == (i == j ? 1.0 : 0.0));
      std::vector<std::vector<double>> pts;
      for (std::size_t s = 0; s < w.size(); s += dim + 1) {
        double sum = 0;
        for (int j = 0; j <= dim; ++j) {
          CHECK(w[s + j] >= 0);
          CHECK(std::abs(w[s + j] * k - std::round(w[s + j] * k)) < 1e-12);
          sum += w[s + j];
        }
        CHECK(sum == Approx(1));
        pts.emplace_back(w.begin() + std::ptrdiff_t(s), w.begin() + std::ptrdiff_t(s + dim + 1));
      }
      std::sort(pts.begin(), pts.end());
      CHECK(std::adjacent_find(pts.begin(), pts.end()) == pts.end()); // no duplicates
    }
}
