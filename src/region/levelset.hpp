// Level-set regions: the zero set of f(x) - value for a formula f written in
// the spec and evaluated with muparser, and the Hessian indicator of seed 002
// §5.3 that keeps only the cells where f curves most.
//
// Spec (region type "levelset"; see levelset.cpp for the exact rules):
//   {"type": "levelset", "expression": "x^2 + y^2", "value": 0.25,
//    "variables": ["x", "y"], "constants": {"a": 1}, "samples": 2,
//    "solid": false, "indicator": {"type": "hessian", "fraction": 0.1}}
#pragma once

#include "bisect/region.hpp"

#include <nlohmann/json_fwd.hpp>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace mu {
class Parser;
} // namespace mu

namespace bisect {

// A compiled formula of `variables.size()` variables (one per mesh
// coordinate, in coordinate order) and named constants. Evaluation is not
// thread-safe (muparser keeps its stack in the parser).
class LevelsetFunction {
public:
  // Throws std::invalid_argument with a one-line message: muparser's syntax
  // error, an unknown variable, a bad or repeated name, an assignment, or an
  // expression that gives more than one value.
  LevelsetFunction(const std::string &expression, const std::vector<std::string> &variables,
                   const std::vector<std::pair<std::string, double>> &constants);
  ~LevelsetFunction();
  LevelsetFunction(LevelsetFunction &&) noexcept;
  LevelsetFunction &operator=(LevelsetFunction &&) noexcept;

  int dim() const { return dim_; }
  // f at the point x (dim() coordinates). May be +-inf or NaN.
  double operator()(const double *x) const;
  // The Hessian of f at x by central differences with step `step` on every
  // axis: H_kk = (f(x+s e_k) - 2 f(x) + f(x-s e_k)) / s^2 and
  // H_kl = (f(x+s e_k+s e_l) - f(x+s e_k-s e_l) - f(x-s e_k+s e_l)
  //         + f(x-s e_k-s e_l)) / (4 s^2), written row after row to H
  // (dim() x dim()). Exact for quadratics up to rounding.
  void hessian(const double *x, double step, double *H) const;

private:
  int dim_ = 0;
  std::unique_ptr<mu::Parser> parser_;
  std::unique_ptr<double[]> vars_; // muparser reads the variables from here
};

// The Hessian step of the indicator, relative to the cell's longest edge.
inline constexpr double kHessianStep = 1e-3;

// Seed 002 §5.3's curvature indicator of one cell (`verts`: dim+1 points):
// e = sum_i |h_i^T H(x_i) h_i|, h_i = x_i - centroid. Each term is one
// central second difference along h_i with a step of length kHessianStep *
// (longest edge): the quadratic form of the Hessian without forming it.
// +inf when any term is not finite (a vertex at or next to a singularity
// ranks first). A vertex at the centroid (impossible in a non-degenerate
// cell) would give NaN, hence +inf.
double hessian_indicator(const LevelsetFunction &f, const double *verts, int dim);

// The barycentric lattice of order k on a simplex of dimension `dim`: every
// (a_0, ..., a_dim) of non-negative integers with sum k, divided by k; the
// dim+1 vertices come first. C(dim+k, dim) points, dim+1 weights each.
std::vector<double> barycentric_lattice(int dim, int k);

// Builds the levelset region of the JSON object `spec` for a mesh of
// dimension `dim`. Errors throw InputError(origin, where + ": " + what).
// `top_level` is false inside union/intersection, where an indicator is
// refused (a set region does not pass its members' filter on).
std::unique_ptr<Region> make_levelset_region(const nlohmann::json &spec, int dim,
                                             const std::string &origin, const std::string &where,
                                             bool top_level);

} // namespace bisect
