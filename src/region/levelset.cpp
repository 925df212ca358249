// Level-set regions (seed 002 §5.3): cells where g = f - value changes sign, f
// a formula from the spec evaluated with muparser; and the Hessian indicator
// that keeps the fraction of those cells where f curves most.
//
// Selection (touches()) is a sampling test: not exact, and not conservative in
// this project's sense (it can miss a cell the zero set touches), but never a
// false "yes" for a continuous g. g is evaluated at the points of the
// barycentric lattice of order k ("samples", default 2) of the closed cell: the
// vertices, and for k >= 2 the points whose barycentric coordinates are
// multiples of 1/k (k = 2 adds the edge midpoints; k = 3 the edge thirds and,
// from 2D up, the face centroids). The cell is selected when some sample has g
// <= 0 and some sample has g >= 0 (a sample with g == 0 alone is enough: the
// closed cell touches the zero set there). With "solid": true it is the
// sublevel set {g <= 0} instead: selected when some sample has g <= 0.
//
//   Never wrong when it says yes (g continuous on the cell): samples of both
//   signs in a convex cell mean the segment between them crosses the zero set.
//   Can miss: a zero set that enters and leaves the cell between samples (every
//   sample on one side), e.g. a small closed surface inside the cell, a surface
//   that grazes a face or dips in through an edge, two sheets of the zero set
//   crossing the same cell. A larger k shrinks the gaps: the lattice splits the
//   cell into k^dim small simplices with edges (x_i - x_j)/k, so every point
//   lies within l/k of a sample (l: the longest edge); if g is L-Lipschitz on
//   the cell, a missed cell has |g| <= L l / k everywhere g has the sign the
//   samples lack: the zero set only dips into it by a sliver thin at the scale
//   l/k. The lattice of order k contains that of every divisor d of k, so
//   selection(d) is part of selection(k). When f is affine (a plane) the
//   vertices decide, exactly, for every k.
//
// Singularities: +-inf keep their sign (the poles of -1/r are -inf, so a cell
// with a pole at a vertex counts as having a negative sample); NaN (0/0,
// sqrt(-1), inf - inf) carries no sign and the sample is skipped; a cell whose
// samples are all NaN is not selected. Across a pole of 1/x the sign flips
// without a zero; such a cell is selected (the test sees signs, not
// continuity).
//
// Indicator: among the cells touches() selected in one iteration (filter()),
// keep round(fraction * n) of them, at least 1, with the largest e = sum_i
// |h_i^T H(x_i) h_i| (seed 002 §5.3), H the Hessian of the indicator's
// expression (default: the region's), h_i = x_i - centroid. Each term is the
// second directional derivative along h_i by one central difference, (f(x_i +
// tau h_i) - 2 f(x_i) + f(x_i - tau h_i)) / tau^2 with |tau h_i| = kHessianStep
// times the cell's longest edge: 3 evaluations per vertex instead of the 2
// dim^2 + 1 of the full difference Hessian (same O(step^2) accuracy; exact for
// quadratics up to rounding). A non-finite e (a vertex at a singularity, or a
// difference stencil straddling one) counts as +inf and ranks first. Ties go to
// the smaller cell id, so the choice is deterministic. The step kHessianStep =
// 1e-3 of the longest edge balances truncation (relative error ~ (step/r)^2 at
// distance r from a singularity) against rounding (~ 1e-16 |f| / step^2).
#include "region/levelset.hpp"

#include "bisect/mesh.hpp"

#include <muParser.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

namespace bisect {
namespace {

using json = nlohmann::json;

constexpr int kMaxDim = 4;
constexpr int kMaxSamples = 16; // lattice order: C(4+16, 4) = 4845 points per pentatope
constexpr int kDefaultSamples = 2;

bool is_identifier(const std::string &s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_'))
    return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

std::string json_quoted(const std::string &s) {
  return json(s).dump();
}

std::string joined(const std::vector<std::string> &names) {
  std::string out;
  for (const std::string &n : names)
    out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

// muparser treats "x = 3" as an assignment to the variable; a region formula
// has no use for it. "==", "<=", ">=" and "!=" are comparisons.
bool has_assignment(const std::string &e) {
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (e[i] != '=')
      continue;
    const char before = i ? e[i - 1] : ' ';
    const char after = i + 1 < e.size() ? e[i + 1] : ' ';
    if (after == '=') {
      ++i; // "=="
      continue;
    }
    if (before != '<' && before != '>' && before != '!')
      return true;
  }
  return false;
}

} // namespace

// ---------------------------------------------------------------------------
// LevelsetFunction

LevelsetFunction::LevelsetFunction(const std::string &expression,
                                   const std::vector<std::string> &variables,
                                   const std::vector<std::pair<std::string, double>> &constants)
    : dim_(int(variables.size())), parser_(std::make_unique<mu::Parser>()),
      vars_(std::make_unique<double[]>(std::max<std::size_t>(1, variables.size()))) {
  std::vector<std::string> seen;
  auto name_ok = [&](const std::string &name, const char *kind) {
    if (!is_identifier(name))
      throw std::invalid_argument(std::string(kind) + " name " + json_quoted(name) +
                                  " is not a name (letters, digits, _; not starting with a digit)");
    if (std::find(seen.begin(), seen.end(), name) != seen.end())
      throw std::invalid_argument("the name " + json_quoted(name) + " is used twice");
    seen.push_back(name);
  };
  std::vector<std::string> const_names;
  try {
    for (std::size_t k = 0; k < variables.size(); ++k) {
      name_ok(variables[k], "variable");
      vars_[k] = 0;
      parser_->DefineVar(variables[k], &vars_[k]);
    }
    for (const auto &[name, value] : constants) {
      name_ok(name, "constant");
      const_names.push_back(name);
      parser_->DefineConst(name, value);
    }
    if (has_assignment(expression))
      throw std::invalid_argument("assignments (=) are not allowed in " + json_quoted(expression) +
                                  "; use == to compare");
    parser_->SetExpr(expression);
    // Parses with undefined names allowed and lists every variable used.
    for (const auto &used : parser_->GetUsedVar())
      if (std::find(variables.begin(), variables.end(), used.first) == variables.end())
        throw std::invalid_argument("unknown variable " + json_quoted(used.first) + " in " +
                                    json_quoted(expression) + " (variables: " + joined(variables) +
                                    "; constants: " + joined(const_names) + ")");
    int results = 0;
    parser_->Eval(results);
    if (results != 1)
      throw std::invalid_argument(json_quoted(expression) + " gives " + std::to_string(results) +
                                  " values (expected one formula, no commas)");
  } catch (const mu::Parser::exception_type &e) {
    std::string msg = e.GetMsg();
    while (!msg.empty() && (msg.back() == '.' || msg.back() == ' '))
      msg.pop_back();
    // muparser reads "foo(x)" as the variable foo and a stray "(".
    const std::size_t paren = std::size_t(std::max(0, e.GetPos()));
    if (e.GetCode() == mu::ecUNEXPECTED_PARENS && paren < expression.size() &&
        expression[paren] == '(') {
      std::size_t end = paren; // one past the name before the parenthesis
      while (end > 0 && std::isspace(static_cast<unsigned char>(expression[end - 1])))
        --end;
      std::size_t begin = end;
      while (begin > 0 && (std::isalnum(static_cast<unsigned char>(expression[begin - 1])) ||
                           expression[begin - 1] == '_'))
        --begin;
      const std::string name = expression.substr(begin, end - begin);
      if (std::find(seen.begin(), seen.end(), name) != seen.end())
        msg = json_quoted(name) + " at position " + std::to_string(begin) +
              " is a variable or constant, not a function (a missing \"*\"?)";
      else if (is_identifier(name) && !parser_->GetFunDef().count(name))
        msg = "unknown function " + json_quoted(name) + " at position " + std::to_string(begin);
    }
    throw std::invalid_argument(msg + " in " + json_quoted(expression));
  }
}

LevelsetFunction::~LevelsetFunction() = default;
LevelsetFunction::LevelsetFunction(LevelsetFunction &&) noexcept = default;
LevelsetFunction &LevelsetFunction::operator=(LevelsetFunction &&) noexcept = default;

double LevelsetFunction::operator()(const double *x) const {
  std::copy(x, x + dim_, vars_.get());
  return parser_->Eval();
}

void LevelsetFunction::hessian(const double *x, double s, double *H) const {
  const int n = dim_;
  const double f0 = (*this)(x);
  auto at = [&](int k, double dk, int l, double dl) {
    double q[kMaxDim] = {};
    std::copy(x, x + n, q);
    q[k] += dk;
    if (l >= 0)
      q[l] += dl;
    return (*this)(q);
  };
  const double s2 = s * s;
  for (int k = 0; k < n; ++k) {
    H[k * n + k] = (at(k, s, -1, 0) - 2 * f0 + at(k, -s, -1, 0)) / s2;
    for (int l = k + 1; l < n; ++l) {
      const double v =
          (at(k, s, l, s) - at(k, s, l, -s) - at(k, -s, l, s) + at(k, -s, l, -s)) / (4 * s2);
      H[k * n + l] = H[l * n + k] = v;
    }
  }
}

double hessian_indicator(const LevelsetFunction &f, const double *verts, int dim) {
  assert(dim == f.dim() && dim <= kMaxDim);
  double c[kMaxDim] = {};
  for (int i = 0; i <= dim; ++i)
    for (int k = 0; k < dim; ++k)
      c[k] += verts[i * dim + k] / (dim + 1);
  double longest2 = 0;
  for (int i = 0; i <= dim; ++i)
    for (int j = i + 1; j <= dim; ++j) {
      double d2 = 0;
      for (int k = 0; k < dim; ++k)
        d2 += (verts[i * dim + k] - verts[j * dim + k]) * (verts[i * dim + k] - verts[j * dim + k]);
      longest2 = std::max(longest2, d2);
    }
  const double step = kHessianStep * std::sqrt(longest2);
  double e = 0;
  for (int i = 0; i <= dim; ++i) {
    // h^T H h = d^2/dtau^2 f(x + tau h) at 0, by the central difference with
    // tau = step / |h| (a step of length `step` along h).
    const double *x = verts + i * dim;
    double h[kMaxDim], plus[kMaxDim] = {}, minus[kMaxDim] = {}, h2 = 0;
    for (int k = 0; k < dim; ++k) {
      h[k] = x[k] - c[k];
      h2 += h[k] * h[k];
    }
    const double tau = step / std::sqrt(h2);
    for (int k = 0; k < dim; ++k) {
      plus[k] = x[k] + tau * h[k];
      minus[k] = x[k] - tau * h[k];
    }
    const double q = (f(plus) - 2 * f(x) + f(minus)) / (tau * tau);
    if (!std::isfinite(q))
      return std::numeric_limits<double>::infinity();
    e += std::abs(q);
  }
  return e;
}

std::vector<double> barycentric_lattice(int dim, int k) {
  std::vector<double> out;
  for (int i = 0; i <= dim; ++i) // the vertices first
    for (int j = 0; j <= dim; ++j)
      out.push_back(i == j ? 1.0 : 0.0);
  std::vector<int> a(dim + 1, 0);
  std::function<void(int, int)> rec = [&](int i, int left) {
    if (i == dim) {
      a[dim] = left;
      if (std::count(a.begin(), a.end(), k) == 1)
        return; // a vertex, already listed
      for (int j = 0; j <= dim; ++j)
        out.push_back(double(a[j]) / k);
      return;
    }
    for (int v = left; v >= 0; --v) {
      a[i] = v;
      rec(i + 1, left - v);
    }
  };
  rec(0, k);
  return out;
}

// ---------------------------------------------------------------------------
// The region

namespace {

class LevelsetRegion final : public Region {
public:
  LevelsetRegion(LevelsetFunction f, double value, int samples, bool solid,
                 std::unique_ptr<LevelsetFunction> indicator, double fraction)
      : f_(std::move(f)), value_(value), solid_(solid), indicator_(std::move(indicator)),
        fraction_(fraction), weights_(barycentric_lattice(f_.dim(), samples)) {}

  bool touches(const double *verts, int dim) const override {
    assert(dim == f_.dim());
    const int n = dim + 1;
    bool below = false, above = false;
    double p[kMaxDim];
    for (std::size_t s = 0; s < weights_.size(); s += n) {
      for (int k = 0; k < dim; ++k) {
        double x = 0;
        for (int i = 0; i < n; ++i)
          x += weights_[s + i] * verts[i * dim + k];
        p[k] = x;
      }
      const double g = f_(p) - value_;
      if (std::isnan(g))
        continue;
      below |= g <= 0;
      above |= g >= 0;
      if (below && (above || solid_))
        return true;
    }
    return false;
  }

  void bounds(double *lo, double *hi, int dim) const override {
    for (int k = 0; k < dim; ++k) {
      lo[k] = -std::numeric_limits<double>::infinity();
      hi[k] = std::numeric_limits<double>::infinity();
    }
  }

  bool filter_ranks_cells() const override { return indicator_ != nullptr && fraction_ < 1; }
  double rank_fraction() const override { return indicator_ ? fraction_ : 1.0; }
  double rank_score(const Mesh &mesh, CellId c) const override {
    if (!indicator_)
      return 0;
    const int dim = mesh.dim;
    double verts[(kMaxDim + 1) * kMaxDim];
    const VertexId *x = mesh.cell(c);
    for (int i = 0; i <= dim; ++i)
      std::copy(mesh.point(x[i]), mesh.point(x[i]) + dim, verts + i * dim);
    return hessian_indicator(*indicator_, verts, dim);
  }

  void filter(const Mesh &mesh, std::vector<CellId> &selected) const override {
    if (!indicator_ || selected.empty())
      return;
    const std::size_t n = selected.size();
    const std::size_t keep =
        std::clamp<std::size_t>(std::size_t(std::llround(fraction_ * double(n))), 1, n);
    if (keep == n)
      return;
    std::vector<std::pair<double, CellId>> ranked(n);
    for (std::size_t j = 0; j < n; ++j)
      ranked[j] = {rank_score(mesh, selected[j]), selected[j]};
    // Ties by the cells' coordinates (cell_coordinates_less), not their ids:
    // a distributed run keeps the same cells.
    auto larger = [&](const std::pair<double, CellId> &a, const std::pair<double, CellId> &b) {
      return a.first > b.first ||
             (a.first == b.first && cell_coordinates_less(mesh, a.second, b.second));
    };
    std::nth_element(ranked.begin(), ranked.begin() + std::ptrdiff_t(keep), ranked.end(), larger);
    selected.resize(keep);
    for (std::size_t j = 0; j < keep; ++j)
      selected[j] = ranked[j].second;
    std::sort(selected.begin(), selected.end());
  }

private:
  LevelsetFunction f_;
  double value_;
  bool solid_;
  std::unique_ptr<LevelsetFunction> indicator_;
  double fraction_;
  std::vector<double> weights_; // dim+1 barycentric weights per sample
};

// Field readers; every error names the file and where the region sits.
struct Fields {
  const json &obj;
  const std::string &origin, &where;

  [[noreturn]] void fail(const std::string &what) const {
    throw InputError(origin, where + ": " + what);
  }
  void only(std::initializer_list<const char *> fields) const {
    for (const auto &item : obj.items()) {
      const std::string &key = item.key();
      if (key == "type" || key == "name" || key == "comment")
        continue;
      if (std::none_of(fields.begin(), fields.end(), [&](const char *f) { return key == f; })) {
        std::string list;
        for (const char *f : fields)
          list += std::string(list.empty() ? "" : ", ") + f;
        fail("unknown field " + json_quoted(key) + " (expected " + list + ", name, comment)");
      }
    }
  }
  const json *find(const char *key) const {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }
  std::string string(const char *key) const {
    const json *v = find(key);
    if (!v)
      fail("missing " + json_quoted(key));
    if (!v->is_string())
      fail(json_quoted(key) + " must be a string");
    return v->get<std::string>();
  }
  double number(const char *key, double fallback) const {
    const json *v = find(key);
    if (!v)
      return fallback;
    if (!v->is_number() || !std::isfinite(v->get<double>()))
      fail(json_quoted(key) + " must be a finite number");
    return v->get<double>();
  }
};

} // namespace

std::unique_ptr<Region> make_levelset_region(const json &spec, int dim, const std::string &origin,
                                             const std::string &where, bool top_level) {
  const Fields in{spec, origin, where};
  in.only({"expression", "value", "variables", "constants", "samples", "solid", "indicator"});
  const std::string expression = in.string("expression");
  const double value = in.number("value", 0.0);

  std::vector<std::string> variables;
  if (const json *v = in.find("variables")) {
    if (!v->is_array() ||
        !std::all_of(v->begin(), v->end(), [](const json &e) { return e.is_string(); }))
      in.fail("\"variables\" must be an array of names, one per mesh coordinate");
    if (int(v->size()) != dim)
      in.fail("\"variables\" has " + std::to_string(v->size()) + " names, the mesh is " +
              std::to_string(dim) + "D (one name per coordinate, time last in space-time)");
    for (const json &e : *v)
      variables.push_back(e.get<std::string>());
  } else {
    const char *names[] = {"x", "y", "z", "t"}; // 2D: x, y; 3D: x, y, z; 4D: x, y, z, t
    variables.assign(names, names + dim);
  }

  const char *kName = " is not a name (letters, digits and _, not starting with a digit)";
  for (std::size_t k = 0; k < variables.size(); ++k) {
    if (!is_identifier(variables[k]))
      in.fail("\"variables\": " + json_quoted(variables[k]) + kName);
    if (std::find(variables.begin(), variables.begin() + std::ptrdiff_t(k), variables[k]) !=
        variables.begin() + std::ptrdiff_t(k))
      in.fail("\"variables\": " + json_quoted(variables[k]) + " is listed twice");
  }

  std::vector<std::pair<std::string, double>> constants;
  if (const json *c = in.find("constants")) {
    if (!c->is_object())
      in.fail("\"constants\" must be an object of names and numbers, e.g. {\"G\": 1}");
    for (const auto &item : c->items()) {
      if (!is_identifier(item.key()))
        in.fail("\"constants\": " + json_quoted(item.key()) + kName);
      if (std::find(variables.begin(), variables.end(), item.key()) != variables.end())
        in.fail("\"constants\": " + json_quoted(item.key()) + " is also a variable");
      if (!item.value().is_number() || !std::isfinite(item.value().get<double>()))
        in.fail("\"constants\": " + json_quoted(item.key()) + " must be a finite number");
      constants.emplace_back(item.key(), item.value().get<double>());
    }
  }

  int samples = kDefaultSamples;
  if (const json *s = in.find("samples")) {
    if (!s->is_number_integer() || s->get<long long>() < 1 || s->get<long long>() > kMaxSamples)
      in.fail("\"samples\" must be a whole number from 1 to " + std::to_string(kMaxSamples) +
              " (the lattice order; 1: vertices only)");
    samples = int(s->get<long long>());
  }
  bool solid = false;
  if (const json *s = in.find("solid")) {
    if (!s->is_boolean())
      in.fail("\"solid\" must be true or false");
    solid = s->get<bool>();
  }

  auto compile = [&](const std::string &text, const std::string &field) {
    try {
      return LevelsetFunction(text, variables, constants);
    } catch (const std::invalid_argument &e) {
      const bool hint =
          !in.find("variables") && std::string(e.what()).find("unknown variable") == 0;
      in.fail(field + ": " + e.what() +
              (hint ? "; \"variables\" names the coordinates, e.g. [\"x\", \"y\", \"t\"]" : ""));
    }
  };
  LevelsetFunction f = compile(expression, "\"expression\"");

  std::unique_ptr<LevelsetFunction> indicator;
  double fraction = 1;
  if (const json *ind = in.find("indicator")) {
    if (!top_level)
      in.fail("an \"indicator\" is only allowed on a levelset region at the top of the spec, "
              "not inside union or intersection");
    if (!ind->is_object())
      in.fail("\"indicator\" must be an object, e.g. {\"type\": \"hessian\", \"fraction\": 0.1}");
    const std::string iwhere = where + ": indicator";
    const Fields ii{*ind, origin, iwhere};
    ii.only({"fraction", "expression"});
    if (ii.string("type") != "hessian")
      ii.fail("unknown indicator type " + json_quoted(ind->at("type").get<std::string>()) +
              " (expected hessian)");
    if (!ii.find("fraction"))
      ii.fail("missing \"fraction\"");
    fraction = ii.number("fraction", 1);
    if (!(fraction > 0 && fraction <= 1))
      ii.fail("\"fraction\" must be in (0, 1]");
    indicator = std::make_unique<LevelsetFunction>(
        ii.find("expression") ? compile(ii.string("expression"), "indicator: \"expression\"")
                              : compile(expression, "\"expression\""));
  }
  return std::make_unique<LevelsetRegion>(std::move(f), value, samples, solid, std::move(indicator),
                                          fraction);
}

} // namespace bisect
