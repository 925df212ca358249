// Regions: a JSON spec read once, then a fast predicate "does this closed
// simplex touch the region?" called for every cell of every iteration.
//
// Exactness of touches(), per region type (all answers are exact up to a
// relative tolerance of about 1e-10 that is applied on the "touches" side, so
// rounding can only add cells, never drop one):
//   sphere         exact: min_{x in T}|x-c| <= r <= max_{x in T}|x-c| (surface)
//                  or min <= r (solid). The max is at a vertex; the min is 0
//                  when T holds c (simplex_holds: scale-free, so a sphere of
//                  any radius > 0 inside a cell selects it), else the
//                  point-to-convex-hull distance (hull_within below), whose
//                  rounding error is about 1e-16 of the distances from c to
//                  T's vertices: a cell that a sphere reaches by less than
//                  that without holding c may be missed.
//   hemisphere     exact: T is clipped by the halfspace x.n >= offset to a
//                  convex polytope P (its vertices: the vertices of T inside
//                  plus the crossings of the edges with the plane); P touches
//                  the surface iff min_P |x-c| <= r <= max_P |x-c|, since P is
//                  connected; both are computed exactly on P's vertex list.
//   box            exact: the linear program "lambda >= 0, sum lambda = 1,
//                  min <= V lambda <= max" is solved (phase 1 of the simplex
//                  method, Bland's rule) when the cheap tests do not decide.
//   halfspace      exact: some vertex satisfies x.n >= offset.
//   moving_sphere  exact: f(x,t) = |x - c0 - v t| is the norm of an affine map,
//                  so over T its max is at a vertex and its min is the distance
//                  from c0 to the hull of the mapped vertices y = x - v t.
//   union          exact if its members are.
//   levelset       sampled (levelset.cpp): never a false "yes", but can miss
//                  a zero set that passes between the samples.
//   intersection   conservative: every member touches T (the members may
//                  touch T in different places, so T can be selected although
//                  it misses their common part).
//
// The kernels are templated on the point dimension and the region classes on
// the mesh dimension (2, 3, 4); parse_region dispatches once. touches() uses
// fixed-size stack arrays only.
#include "bisect/region.hpp"

#include "bisect/mesh.hpp"
#include "core/geometry.hpp"
#include "region/levelset.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

namespace bisect {
namespace {

using json = nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxDim = 4;
// Points of a simplex clipped by a halfspace: at most 3 inside + 3*2 crossings
// for a pentatope.
constexpr int kMaxHullPoints = 9;
// A face is dropped as affinely dependent when a new edge has less than this
// fraction of its squared length outside the span of the previous edges.
constexpr double kDependent = 1e-13;
// Barycentric coordinates down to -kBary still count as inside a face.
constexpr double kBary = 1e-12;
// Relative slack on radii, applied in the "touches" direction.
constexpr double kRadiusSlack = 1e-10;

// ---------------------------------------------------------------------------
// Geometry kernels on points of M coordinates.

using geometry::dot;
using geometry::squared_distance;

// Squared distance from p to the box [lo, hi] (a lower bound for the distance
// to anything inside the box).
template <int M> double box_dist2(const double *p, const double *lo, const double *hi) {
  double s = 0;
  for (int k = 0; k < M; ++k) {
    const double d = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
    s += d * d;
  }
  return s;
}

// Bounding box of n points.
template <int M> void point_bbox(const double *pts, int n, double *lo, double *hi) {
  for (int k = 0; k < M; ++k)
    lo[k] = hi[k] = pts[k];
  for (int i = 1; i < n; ++i)
    for (int k = 0; k < M; ++k) {
      lo[k] = std::min(lo[k], pts[i * M + k]);
      hi[k] = std::max(hi[k], pts[i * M + k]);
    }
}

// Squared distance from p to its orthogonal projection q onto the affine hull
// of the k+1 points pts[idx[0..k]], or -1 when q falls outside their convex
// hull (a barycentric coordinate < -kBary) or the points are affinely
// dependent. Normal equations G lambda = b with G_ij = e_i.e_j, e_i = x_i - x_0,
// b_i = e_i.(p - x_0), solved by Cholesky (G is at most 4x4).
template <int M> double face_dist2(const double *p, const double *pts, const int *idx, int k) {
  double e[M][M], w[M], L[M][M], lam[M];
  const double *x0 = pts + idx[0] * M;
  for (int i = 0; i < k; ++i)
    for (int a = 0; a < M; ++a)
      e[i][a] = pts[idx[i + 1] * M + a] - x0[a];
  for (int a = 0; a < M; ++a)
    w[a] = p[a] - x0[a];
  for (int j = 0; j < k; ++j) {
    const double g = dot<M>(e[j], e[j]);
    double s = g;
    for (int q = 0; q < j; ++q)
      s -= L[j][q] * L[j][q];
    if (!(s > kDependent * g))
      return -1;
    L[j][j] = std::sqrt(s);
    for (int i = j + 1; i < k; ++i) {
      double t = dot<M>(e[i], e[j]);
      for (int q = 0; q < j; ++q)
        t -= L[i][q] * L[j][q];
      L[i][j] = t / L[j][j];
    }
  }
  for (int j = 0; j < k; ++j) { // L y = b
    double t = dot<M>(e[j], w);
    for (int q = 0; q < j; ++q)
      t -= L[j][q] * lam[q];
    lam[j] = t / L[j][j];
  }
  double sum = 0;
  for (int j = k - 1; j >= 0; --j) { // L^T lambda = y
    double t = lam[j];
    for (int q = j + 1; q < k; ++q)
      t -= L[q][j] * lam[q];
    lam[j] = t / L[j][j];
    if (lam[j] < -kBary)
      return -1;
    sum += lam[j];
  }
  if (sum > 1 + kBary)
    return -1; // lambda_0 = 1 - sum < 0
  for (int j = 0; j < k; ++j)
    for (int a = 0; a < M; ++a)
      w[a] -= lam[j] * e[j][a];
  return dot<M>(w, w);
}

// Is the distance from p to the convex hull of the n points (n <= 9) at most
// sqrt(r2)? Exact: the nearest point of the hull lies in the relative interior
// of the hull of some affinely independent subset (Caratheodory), where it is
// the orthogonal projection of p onto that subset's affine hull. So it is
// found by trying every subset of at most M+1 points; every candidate kept is
// a point of the hull, so an early "yes" is always right.
template <int M> bool hull_within(const double *p, const double *pts, int n, double r2) {
  assert(n <= kMaxHullPoints);
  for (int i = 0; i < n; ++i)
    if (squared_distance<M>(p, pts + i * M) <= r2)
      return true;
  int idx[kMaxHullPoints];
  for (unsigned mask = 3; mask < (1u << n); ++mask) {
    const int size = std::popcount(mask);
    if (size < 2 || size > M + 1)
      continue;
    int m = 0;
    for (int i = 0; i < n; ++i)
      if (mask & (1u << i))
        idx[m++] = i;
    const double d2 = face_dist2<M>(p, pts, idx, size - 1);
    if (d2 >= 0 && d2 <= r2)
      return true;
  }
  return false;
}

// Is c in the closed simplex of the D+1 points (up to kBary in barycentric
// coordinates)? Scale-free: the barycentric coordinates are solved from the
// vertices' offsets from c, by elimination with partial pivoting, so their
// error is relative to the simplex's own size and position, whatever the
// distance from c to a vertex compared with a radius. This decides regions far
// smaller than the cell that hold c (a sphere of radius 1e-300 inside a cell
// of size 1 at coordinates 1e6).
template <int D> bool simplex_holds(const double *c, const double *verts) {
  double a[D][D + 1];
  for (int r = 0; r < D; ++r) {
    for (int j = 0; j < D; ++j)
      a[r][j] = (verts[(j + 1) * D + r] - c[r]) - (verts[r] - c[r]);
    a[r][D] = -(verts[r] - c[r]); // c - v0, from the offsets
  }
  for (int k = 0; k < D; ++k) {
    int p = k;
    for (int i = k + 1; i < D; ++i)
      if (std::abs(a[i][k]) > std::abs(a[p][k]))
        p = i;
    if (!(std::abs(a[p][k]) > 0))
      return false; // degenerate: leave it to the distance tests
    if (p != k)
      for (int j = 0; j <= D; ++j)
        std::swap(a[k][j], a[p][j]);
    for (int i = k + 1; i < D; ++i) {
      const double f = a[i][k] / a[k][k];
      for (int j = k; j <= D; ++j)
        a[i][j] -= f * a[k][j];
    }
  }
  double lam[D], sum = 0;
  for (int k = D - 1; k >= 0; --k) {
    double t = a[k][D];
    for (int j = k + 1; j < D; ++j)
      t -= a[k][j] * lam[j];
    lam[k] = t / a[k][k];
    if (!(lam[k] >= -kBary))
      return false;
    sum += lam[k];
  }
  return sum <= 1 + kBary;
}

// Does the convex hull of the n points touch the sphere |x - c| = r? The hull
// is connected, so iff min <= r <= max; the max is at a point of the list.
// `r2lo`/`r2hi` are r^2 shrunk/grown by the slack.
template <int M>
bool hull_meets_sphere(const double *c, double r2lo, double r2hi, const double *pts, int n) {
  double dmin = kInf, dmax = 0;
  for (int i = 0; i < n; ++i) {
    const double d = squared_distance<M>(c, pts + i * M);
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  if (dmax < r2lo)
    return false; // strictly inside the ball
  if (dmin <= r2hi)
    return true;       // points on both sides
  double lo[M], hi[M]; // all points outside: does the ball reach the hull?
  point_bbox<M>(pts, n, lo, hi);
  if (box_dist2<M>(c, lo, hi) > r2hi)
    return false;
  // A simplex holding c touches the sphere: some point is at least r away.
  if (n == M + 1 && simplex_holds<M>(c, pts))
    return true;
  return hull_within<M>(c, pts, n, r2hi);
}

// Does the convex hull of the n points touch the closed ball |x - c| <= r?
template <int M> bool hull_meets_ball(const double *c, double r2hi, const double *pts, int n) {
  double lo[M], hi[M];
  point_bbox<M>(pts, n, lo, hi);
  if (box_dist2<M>(c, lo, hi) > r2hi)
    return false;
  if (n == M + 1 && simplex_holds<M>(c, pts))
    return true;
  return hull_within<M>(c, pts, n, r2hi);
}

// Is there lambda >= 0 with sum lambda = 1 and lo <= V lambda <= hi, i.e. does
// the simplex with vertices V meet the box? Phase 1 of the simplex method on a
// dense tableau (rows: the sum, then "+ slack = hi" and "- surplus = lo" per
// coordinate, each with an artificial variable), Bland's rule so it cannot
// cycle. Coordinates are first centred on the box and scaled to O(1).
// Feasible iff the sum of the artificials reaches ~0.
template <int D> bool simplex_meets_box(const double *verts, const double *lo, const double *hi) {
  constexpr int N = D + 1, R = 2 * D + 1, S = N + 2 * D, C = S + R; // column C: right-hand side
  double ctr[D], scale = 0;
  for (int k = 0; k < D; ++k) {
    ctr[k] = 0.5 * (lo[k] + hi[k]);
    scale = std::max(scale, 0.5 * (hi[k] - lo[k]));
  }
  for (int i = 0; i < N; ++i)
    for (int k = 0; k < D; ++k)
      scale = std::max(scale, std::abs(verts[i * D + k] - ctr[k]));
  if (!(scale > 0))
    return true; // everything is one point

  double T[R][C + 1] = {};
  int basis[R];
  for (int i = 0; i < N; ++i)
    T[0][i] = 1;
  T[0][C] = 1;
  for (int k = 0; k < D; ++k) {
    for (int i = 0; i < N; ++i)
      T[1 + 2 * k][i] = T[2 + 2 * k][i] = (verts[i * D + k] - ctr[k]) / scale;
    T[1 + 2 * k][N + 2 * k] = 1;
    T[2 + 2 * k][N + 2 * k + 1] = -1;
    T[1 + 2 * k][C] = (hi[k] - ctr[k]) / scale;
    T[2 + 2 * k][C] = (lo[k] - ctr[k]) / scale;
  }
  for (int r = 0; r < R; ++r) {
    if (T[r][C] < 0)
      for (int j = 0; j <= C; ++j)
        T[r][j] = -T[r][j];
    T[r][S + r] = 1;
    basis[r] = S + r;
  }
  // Reduced costs of "minimize the sum of the artificials"; cost[C] = -objective.
  double cost[C + 1] = {};
  for (int j = 0; j <= C; ++j)
    if (j < S || j == C)
      for (int r = 0; r < R; ++r)
        cost[j] -= T[r][j];

  constexpr double kPivot = 1e-11;
  for (int iter = 0; iter < 100; ++iter) {
    int enter = -1;
    for (int j = 0; j < C && enter < 0; ++j)
      if (cost[j] < -kPivot)
        enter = j;
    if (enter < 0)
      break;
    int leave = -1;
    double best = kInf;
    for (int r = 0; r < R; ++r) {
      if (T[r][enter] <= kPivot)
        continue;
      const double ratio = T[r][C] / T[r][enter];
      if (leave < 0 || ratio < best - 1e-14 || (ratio <= best + 1e-14 && basis[r] < basis[leave])) {
        best = ratio;
        leave = r;
      }
    }
    if (leave < 0)
      break; // cannot happen: the objective is bounded below by 0
    const double piv = T[leave][enter];
    for (int j = 0; j <= C; ++j)
      T[leave][j] /= piv;
    for (int r = 0; r < R; ++r) {
      if (r == leave || T[r][enter] == 0)
        continue;
      const double f = T[r][enter];
      for (int j = 0; j <= C; ++j)
        T[r][j] -= f * T[leave][j];
    }
    const double f = cost[enter];
    for (int j = 0; j <= C; ++j)
      cost[j] -= f * T[leave][j];
    basis[leave] = enter;
  }
  // Also reached (conservatively "yes") if the iteration cap were ever hit
  // with a tiny remaining infeasibility.
  return -cost[C] <= 1e-9;
}

// ---------------------------------------------------------------------------
// Region types. `D` is the mesh dimension; `verts` holds D+1 points.

template <int D> class SphereRegion final : public Region {
public:
  bool concurrent() const override { return true; }
  bool monotone() const override { return true; }
  SphereRegion(const std::vector<double> &c, double r, bool solid) : r_(r), solid_(solid) {
    std::copy(c.begin(), c.end(), c_);
    r2lo_ = r * r * (1 - kRadiusSlack);
    r2hi_ = r * r * (1 + kRadiusSlack);
  }
  bool touches(const double *verts, [[maybe_unused]] int dim) const override {
    assert(dim == D);
    return solid_ ? hull_meets_ball<D>(c_, r2hi_, verts, D + 1)
                  : hull_meets_sphere<D>(c_, r2lo_, r2hi_, verts, D + 1);
  }
  void bounds(double *lo, double *hi, int) const override {
    for (int k = 0; k < D; ++k) {
      lo[k] = c_[k] - r_;
      hi[k] = c_[k] + r_;
    }
  }

private:
  double c_[D], r_, r2lo_, r2hi_;
  bool solid_;
};

template <int D> class HemisphereRegion final : public Region {
public:
  bool concurrent() const override { return true; }
  bool monotone() const override { return true; }
  HemisphereRegion(const std::vector<double> &c, double r, const std::vector<double> &n,
                   double offset)
      : r_(r), offset_(offset) {
    std::copy(c.begin(), c.end(), c_);
    std::copy(n.begin(), n.end(), n_);
    r2lo_ = r * r * (1 - kRadiusSlack);
    r2hi_ = r * r * (1 + kRadiusSlack);
  }
  bool touches(const double *verts, [[maybe_unused]] int dim) const override {
    assert(dim == D);
    double s[D + 1];
    int inside = 0;
    for (int i = 0; i <= D; ++i) {
      s[i] = dot<D>(verts + i * D, n_) - offset_;
      inside += s[i] >= 0;
    }
    if (inside == 0)
      return false;
    if (inside == D + 1)
      return hull_meets_sphere<D>(c_, r2lo_, r2hi_, verts, D + 1);
    // Clip: the vertices inside, and where the edges cross the plane.
    double pts[kMaxHullPoints * D];
    int n = 0;
    for (int i = 0; i <= D; ++i)
      if (s[i] >= 0)
        std::copy(verts + i * D, verts + i * D + D, pts + D * n++);
    for (int i = 0; i <= D; ++i) {
      if (!(s[i] > 0))
        continue;
      for (int j = 0; j <= D; ++j) {
        if (!(s[j] < 0))
          continue;
        const double t = s[i] / (s[i] - s[j]);
        for (int k = 0; k < D; ++k)
          pts[D * n + k] = verts[i * D + k] + t * (verts[j * D + k] - verts[i * D + k]);
        ++n;
      }
    }
    return hull_meets_sphere<D>(c_, r2lo_, r2hi_, pts, n);
  }
  // The sphere's box, cut by the plane when the normal is along an axis.
  void bounds(double *lo, double *hi, int) const override {
    int axis = -1, nonzero = 0;
    for (int k = 0; k < D; ++k)
      if (n_[k] != 0) {
        axis = k;
        ++nonzero;
      }
    for (int k = 0; k < D; ++k) {
      lo[k] = c_[k] - r_;
      hi[k] = c_[k] + r_;
    }
    if (nonzero == 1) {
      const double cut = offset_ / n_[axis];
      if (n_[axis] > 0)
        lo[axis] = std::max(lo[axis], cut);
      else
        hi[axis] = std::min(hi[axis], cut);
    }
  }

private:
  double c_[D], n_[D], r_, r2lo_, r2hi_, offset_;
};

template <int D> class BoxRegion final : public Region {
public:
  bool concurrent() const override { return true; }
  bool monotone() const override { return true; }
  BoxRegion(const std::vector<double> &lo, const std::vector<double> &hi) {
    std::copy(lo.begin(), lo.end(), lo_);
    std::copy(hi.begin(), hi.end(), hi_);
  }
  bool touches(const double *verts, [[maybe_unused]] int dim) const override {
    assert(dim == D);
    double lo[D], hi[D];
    point_bbox<D>(verts, D + 1, lo, hi);
    for (int k = 0; k < D; ++k)
      if (hi[k] < lo_[k] || lo[k] > hi_[k])
        return false;
    for (int i = 0; i <= D; ++i)
      if (box_dist2<D>(verts + i * D, lo_, hi_) == 0)
        return true;
    bool bbox_inside = true; // the box holds the simplex's bounding box
    for (int k = 0; k < D; ++k)
      bbox_inside &= lo[k] >= lo_[k] && hi[k] <= hi_[k];
    return bbox_inside || simplex_meets_box<D>(verts, lo_, hi_);
  }
  void bounds(double *lo, double *hi, int) const override {
    std::copy(lo_, lo_ + D, lo);
    std::copy(hi_, hi_ + D, hi);
  }

private:
  double lo_[D], hi_[D];
};

template <int D> class HalfspaceRegion final : public Region {
public:
  bool concurrent() const override { return true; }
  bool monotone() const override { return true; }
  HalfspaceRegion(const std::vector<double> &n, double offset) : offset_(offset) {
    std::copy(n.begin(), n.end(), n_);
  }
  bool touches(const double *verts, [[maybe_unused]] int dim) const override {
    assert(dim == D);
    for (int i = 0; i <= D; ++i)
      if (dot<D>(verts + i * D, n_) >= offset_)
        return true;
    return false;
  }
  // Unbounded, except on the axis of an axis-aligned normal.
  void bounds(double *lo, double *hi, int) const override {
    int axis = -1, nonzero = 0;
    for (int k = 0; k < D; ++k) {
      lo[k] = -kInf;
      hi[k] = kInf;
      if (n_[k] != 0) {
        axis = k;
        ++nonzero;
      }
    }
    if (nonzero == 1)
      (n_[axis] > 0 ? lo[axis] : hi[axis]) = offset_ / n_[axis];
  }

private:
  double n_[D], offset_;
};

// Space-time: coordinates (x_1..x_{D-1}, t); the sphere |x - c0 - v t| = r.
template <int D> class MovingSphereRegion final : public Region {
  static constexpr int M = D - 1; // space dimensions
public:
  bool concurrent() const override { return true; }
  bool monotone() const override { return true; }
  MovingSphereRegion(const std::vector<double> &c, const std::vector<double> &v, double r,
                     bool solid)
      : r_(r), solid_(solid) {
    std::copy(c.begin(), c.end(), c_);
    std::copy(v.begin(), v.end(), v_);
    r2lo_ = r * r * (1 - kRadiusSlack);
    r2hi_ = r * r * (1 + kRadiusSlack);
  }
  bool touches(const double *verts, [[maybe_unused]] int dim) const override {
    assert(dim == D);
    double y[(D + 1) * M]; // y = x - v t: the sphere stands still
    for (int i = 0; i <= D; ++i)
      for (int k = 0; k < M; ++k)
        y[i * M + k] = verts[i * D + k] - v_[k] * verts[i * D + M];
    return solid_ ? hull_meets_ball<M>(c_, r2hi_, y, D + 1)
                  : hull_meets_sphere<M>(c_, r2lo_, r2hi_, y, D + 1);
  }
  // Time is unbounded; so is every space axis the sphere moves along.
  void bounds(double *lo, double *hi, int) const override {
    for (int k = 0; k < D; ++k) {
      const bool fixed = k < M && v_[k] == 0;
      lo[k] = fixed ? c_[k] - r_ : -kInf;
      hi[k] = fixed ? c_[k] + r_ : kInf;
    }
  }

private:
  double c_[M], v_[M], r_, r2lo_, r2hi_;
  bool solid_;
};

// Union (any member touches) or intersection (every member touches: a
// conservative answer, see the top of the file).
class SetRegion final : public Region {
public:
  bool concurrent() const override {
    return std::all_of(members_.begin(), members_.end(),
                       [](const auto &m) { return m->concurrent(); });
  }
  // An intersection too: a cell every member touches lies in cells they all do.
  bool monotone() const override {
    return std::all_of(members_.begin(), members_.end(),
                       [](const auto &m) { return m->monotone(); });
  }
  SetRegion(std::vector<std::unique_ptr<Region>> members, int dim, bool all)
      : members_(std::move(members)), all_(all) {
    for (const auto &m : members_) {
      std::array<double, 2 * kMaxDim> b{};
      m->bounds(b.data(), b.data() + kMaxDim, dim);
      member_bounds_.push_back(b);
    }
  }
  bool touches(const double *verts, int dim) const override {
    double lo[kMaxDim], hi[kMaxDim];
    for (int k = 0; k < dim; ++k) {
      lo[k] = hi[k] = verts[k];
      for (int i = 1; i <= dim; ++i) {
        lo[k] = std::min(lo[k], verts[i * dim + k]);
        hi[k] = std::max(hi[k], verts[i * dim + k]);
      }
    }
    for (std::size_t m = 0; m < members_.size(); ++m) {
      const double *b = member_bounds_[m].data();
      bool hit = true;
      for (int k = 0; k < dim && hit; ++k)
        hit = hi[k] >= b[k] && lo[k] <= b[kMaxDim + k];
      hit = hit && members_[m]->touches(verts, dim);
      if (hit != all_)
        return hit;
    }
    return all_;
  }
  void bounds(double *lo, double *hi, int dim) const override {
    for (int k = 0; k < dim; ++k) {
      lo[k] = all_ ? -kInf : kInf;
      hi[k] = all_ ? kInf : -kInf;
      for (const auto &b : member_bounds_) {
        lo[k] = all_ ? std::max(lo[k], b[k]) : std::min(lo[k], b[k]);
        hi[k] = all_ ? std::min(hi[k], b[kMaxDim + k]) : std::max(hi[k], b[kMaxDim + k]);
      }
    }
  }

private:
  std::vector<std::unique_ptr<Region>> members_;
  std::vector<std::array<double, 2 * kMaxDim>> member_bounds_;
  bool all_;
};

// ---------------------------------------------------------------------------
// Parsing and validation. Every message names the file, where the region sits
// in the spec ("regions[1].regions[0]: box: ...") and the field.

constexpr const char *kTypes =
    "sphere, hemisphere, box, halfspace, moving_sphere, levelset, union, intersection";
constexpr int kMaxNesting = 64;

struct Parser {
  const std::string &origin;
  int dim;

  [[noreturn]] void fail(const std::string &where, const std::string &what) const {
    throw InputError(origin, where.empty() ? what : where + ": " + what);
  }

  static std::string quoted(const std::string &s) { return "\"" + s + "\""; }

  // Only the fields of the type, plus "type", "name" and "comment".
  void check_fields(const json &obj, const std::string &where,
                    std::initializer_list<const char *> fields) const {
    for (const auto &item : obj.items()) {
      const std::string &key = item.key();
      if (key == "type" || key == "name" || key == "comment")
        continue;
      bool known = false;
      for (const char *f : fields)
        known |= key == f;
      if (known)
        continue;
      std::string list;
      for (const char *f : fields)
        list += std::string(list.empty() ? "" : ", ") + f;
      fail(where, "unknown field " + quoted(key) + " (expected " + list + ", name, comment)");
    }
  }

  const json &field(const json &obj, const std::string &where, const char *key) const {
    auto it = obj.find(key);
    if (it == obj.end())
      fail(where, "missing " + quoted(key));
    return *it;
  }

  double number(const json &obj, const std::string &where, const char *key) const {
    const json &v = field(obj, where, key);
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      fail(where, quoted(key) + " must be a finite number");
    return v.get<double>();
  }

  double radius(const json &obj, const std::string &where) const {
    const json &v = field(obj, where, "radius");
    if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() > 0))
      fail(where, "\"radius\" must be a positive number");
    return v.get<double>();
  }

  bool flag(const json &obj, const std::string &where, const char *key) const {
    auto it = obj.find(key);
    if (it == obj.end())
      return false;
    if (!it->is_boolean())
      fail(where, quoted(key) + " must be true or false");
    return it->get<bool>();
  }

  // An array of exactly `n` finite numbers; `expected` explains n.
  std::vector<double> vec(const json &obj, const std::string &where, const char *key, int n,
                          const std::string &expected) const {
    const json &v = field(obj, where, key);
    if (!v.is_array())
      fail(where, quoted(key) + " must be an array of " + std::to_string(n) + " numbers");
    if (int(v.size()) != n)
      fail(where, quoted(key) + " has " + std::to_string(v.size()) +
                      (v.size() == 1 ? " entry, " : " entries, ") + expected);
    std::vector<double> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
        fail(where, quoted(key) + " entry " + std::to_string(i) + " must be a finite number");
      out.push_back(v[i].get<double>());
    }
    return out;
  }

  std::vector<double> point(const json &obj, const std::string &where, const char *key) const {
    return vec(obj, where, key, dim, "the mesh is " + std::to_string(dim) + "D");
  }

  std::vector<double> normal(const json &obj, const std::string &where) const {
    std::vector<double> n = point(obj, where, "normal");
    if (std::all_of(n.begin(), n.end(), [](double x) { return x == 0; }))
      fail(where, "\"normal\" must not be zero");
    return n;
  }

  // Builds Region<D> for the mesh dimension.
  template <template <int> class R, class... Args>
  std::unique_ptr<Region> make(Args &&...args) const {
    switch (dim) {
    case 2:
      return std::make_unique<R<2>>(std::forward<Args>(args)...);
    case 3:
      return std::make_unique<R<3>>(std::forward<Args>(args)...);
    default:
      return std::make_unique<R<4>>(std::forward<Args>(args)...);
    }
  }

  std::unique_ptr<Region> region(const json &obj, const std::string &path, int depth) const {
    if (!obj.is_object())
      fail(path, "a region must be a JSON object with a \"type\" field");
    if (depth > kMaxNesting)
      fail(path, "regions nested more than " + std::to_string(kMaxNesting) + " deep");
    auto t = obj.find("type");
    if (t == obj.end())
      fail(path, "missing \"type\" (expected one of " + std::string(kTypes) + ")");
    if (!t->is_string())
      fail(path, "\"type\" must be a string (one of " + std::string(kTypes) + ")");
    const std::string type = t->get<std::string>();
    const std::string where = path.empty() ? type : path + ": " + type;

    if (type == "sphere") {
      check_fields(obj, where, {"center", "radius", "solid"});
      return make<SphereRegion>(point(obj, where, "center"), radius(obj, where),
                                flag(obj, where, "solid"));
    }
    if (type == "hemisphere") {
      check_fields(obj, where, {"center", "radius", "normal", "offset"});
      return make<HemisphereRegion>(point(obj, where, "center"), radius(obj, where),
                                    normal(obj, where), number(obj, where, "offset"));
    }
    if (type == "box") {
      check_fields(obj, where, {"min", "max"});
      const std::vector<double> lo = point(obj, where, "min"), hi = point(obj, where, "max");
      for (int k = 0; k < dim; ++k)
        if (lo[k] > hi[k])
          fail(where, "\"min\" exceeds \"max\" in coordinate " + std::to_string(k) + " (" +
                          json(lo[k]).dump() + " > " + json(hi[k]).dump() + ")");
      return make<BoxRegion>(lo, hi);
    }
    if (type == "halfspace") {
      check_fields(obj, where, {"normal", "offset"});
      return make<HalfspaceRegion>(normal(obj, where), number(obj, where, "offset"));
    }
    if (type == "moving_sphere") {
      check_fields(obj, where, {"center", "velocity", "radius", "solid"});
      if (dim < 3)
        fail(where, "needs a space-time mesh (3D or 4D, time last); the mesh is " +
                        std::to_string(dim) + "D");
      const std::string expected = "expected " + std::to_string(dim - 1) +
                                   " (the space dimensions of a " + std::to_string(dim) +
                                   "D space-time mesh)";
      auto c = vec(obj, where, "center", dim - 1, expected);
      auto v = vec(obj, where, "velocity", dim - 1, expected);
      const double r = radius(obj, where);
      const bool solid = flag(obj, where, "solid");
      if (dim == 3)
        return std::make_unique<MovingSphereRegion<3>>(c, v, r, solid);
      return std::make_unique<MovingSphereRegion<4>>(c, v, r, solid);
    }
    if (type == "levelset") // levelset.cpp: a formula's zero set, sampled
      return make_levelset_region(obj, dim, origin, where, path.empty());
    if (type == "union" || type == "intersection") {
      check_fields(obj, where, {"regions"});
      const json &list = field(obj, where, "regions");
      if (!list.is_array() || list.empty())
        fail(where, "\"regions\" must be a non-empty array of regions");
      std::vector<std::unique_ptr<Region>> members;
      for (std::size_t i = 0; i < list.size(); ++i)
        members.push_back(
            region(list[i], (path.empty() ? "" : path + ".") + "regions[" + std::to_string(i) + "]",
                   depth + 1));
      return std::make_unique<SetRegion>(std::move(members), dim, type == "intersection");
    }
    fail(path, "unknown region type " + quoted(type) + " (expected " + kTypes + ")");
  }
};

// "line L, column C" of the 1-based byte position nlohmann reports.
std::string line_column(const std::string &text, std::size_t byte) {
  const std::size_t end = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < end; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}

// nlohmann's message without its "[json.exception...] parse error at ...: " prefix.
std::string parse_detail(const std::string &what) {
  std::size_t p = what.find("parse error");
  if (p != std::string::npos)
    p = what.find(": ", p);
  return p == std::string::npos ? what : what.substr(p + 2);
}

} // namespace

std::unique_ptr<Region> parse_region(const std::string &json_text, int dim,
                                     const std::string &origin) {
  if (dim < 2 || dim > kMaxDim)
    throw InputError(origin, "regions need a 2D, 3D or 4D mesh, not " + std::to_string(dim) + "D");
  if (json_text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(origin, "empty region spec (expected a JSON object with a \"type\" field)");
  json spec;
  try {
    spec = json::parse(json_text);
  } catch (const json::parse_error &e) {
    throw InputError(origin,
                     line_column(json_text, e.byte) + ": invalid JSON: " + parse_detail(e.what()));
  } catch (const json::exception &e) { // e.g. a number too large for a double
    const std::string what = e.what();
    throw InputError(origin, "invalid JSON: " + what.substr(what.find("] ") == std::string::npos
                                                                ? 0
                                                                : what.find("] ") + 2));
  }
  if (!spec.is_object())
    throw InputError(origin, "the region spec must be a JSON object with a \"type\" field, not " +
                                 std::string(spec.type_name()));
  return Parser{origin, dim}.region(spec, "", 0);
}

std::unique_ptr<Region> read_region(const std::string &path, int dim) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputError(path, "cannot open: no such file");
  if (fs::is_directory(st))
    throw InputError(path, "is a directory");
  // A FIFO would block, a device could be endless: regions are small files.
  if (!fs::is_regular_file(st))
    throw InputError(path, "not a regular file (a region spec is a JSON file)");
  constexpr std::uintmax_t kMaxRegionBytes = 64u << 20;
  if (fs::file_size(path, ec) > kMaxRegionBytes)
    throw InputError(path, "larger than 64 MiB; a region spec is a small JSON file");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, "cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    throw InputError(path, "read error");
  return parse_region(text.str(), dim, path);
}

} // namespace bisect
