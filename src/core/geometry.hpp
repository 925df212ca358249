// Small geometry on points of M coordinates, shared by the layers (one copy
// each; internal, header-only in core).
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <cmath>

namespace bisect::geometry {

template <int M> constexpr double dot(const double *a, const double *b) {
  double s = 0;
  for (int k = 0; k < M; ++k)
    s += a[k] * b[k];
  return s;
}

template <int M> constexpr double squared_distance(const double *a, const double *b) {
  double s = 0;
  for (int k = 0; k < M; ++k)
    s += (a[k] - b[k]) * (a[k] - b[k]);
  return s;
}

// The same for a dimension known at run time.
inline double squared_distance(const double *a, const double *b, int m) {
  double s = 0;
  for (int k = 0; k < m; ++k)
    s += (a[k] - b[k]) * (a[k] - b[k]);
  return s;
}

constexpr double factorial(int n) {
  return n <= 1 ? 1.0 : n * factorial(n - 1);
}

// Determinant of a Dim x Dim matrix (row-major). Closed forms: for 4, the
// Laplace expansion by the 2 x 2 minors of the first two rows and of the last
// two (40 multiplications, no branches; the elimination with pivoting it
// replaced was 15% of a 4D run). Its rounding error, a few units of
// |a| |b| |c| |d| * 1e-16, stays far below the degeneracy threshold 1e-14 * l^4.
template <int Dim> double determinant(std::array<double, Dim * Dim> a) {
  static_assert(Dim >= 2 && Dim <= 4);
  if constexpr (Dim == 4) {
    const double *r0 = &a[0], *r1 = &a[4], *r2 = &a[8], *r3 = &a[12];
    auto minor = [](const double *x, const double *y, int i, int j) {
      return x[i] * y[j] - x[j] * y[i];
    };
    return minor(r0, r1, 0, 1) * minor(r2, r3, 2, 3) - minor(r0, r1, 0, 2) * minor(r2, r3, 1, 3) +
           minor(r0, r1, 0, 3) * minor(r2, r3, 1, 2) + minor(r0, r1, 1, 2) * minor(r2, r3, 0, 3) -
           minor(r0, r1, 1, 3) * minor(r2, r3, 0, 2) + minor(r0, r1, 2, 3) * minor(r2, r3, 0, 1);
  } else if constexpr (Dim == 2) {
    return a[0] * a[3] - a[1] * a[2];
  } else if constexpr (Dim == 3) {
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
  }
}

// det A with A = [x1-x0, ..., xn-x0] (edge vectors as columns).
template <int Dim> double edge_determinant(const double *verts) {
  std::array<double, Dim * Dim> a;
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j)
      a[i * Dim + j] = verts[(j + 1) * Dim + i] - verts[i];
  return determinant<Dim>(a);
}

// Signed volume of the simplex with vertex rows verts[0..Dim].
template <int Dim> double signed_volume(const double *verts) {
  return edge_determinant<Dim>(verts) / factorial(Dim);
}

// With W the edge matrix of the unit equilateral simplex, W^T W = (I + 11^T)/2,
// so (W^T W)^-1 = 2 (I - 11^T/(n+1)) and
//   |S|_F^2 = tr(A^T A (W^T W)^-1) = 2/(n+1) * sum over all vertex pairs |xi-xj|^2,
//   det S   = det A / det W,  det W = sqrt(n+1) / 2^(n/2).
// This is exactly q = n |det S|^(2/n) / |S|_F^2, written so that it does not
// depend on the vertex order (tests compare it with an explicit A W^-1).
// mean_ratio_of takes det = edge_determinant<Dim>(verts) and sum_sq =
// squared_edge_sum<Dim>(verts), for callers that have them already.
template <int Dim> double squared_edge_sum(const double *verts) {
  double sum_sq = 0;
  for (int i = 0; i <= Dim; ++i)
    for (int j = i + 1; j <= Dim; ++j)
      sum_sq += squared_distance<Dim>(verts + i * Dim, verts + j * Dim);
  return sum_sq;
}

template <int Dim> double mean_ratio_of(double det, double sum_sq) {
  constexpr int n = Dim;
  if (!(sum_sq > 0))
    return 0;
  const double det_w = std::sqrt(double(n + 1)) / std::pow(2.0, 0.5 * n);
  const double r = std::abs(det) / det_w; // |det S|
  double r_2n;                            // |det S|^(2/n)
  if constexpr (n == 2)
    r_2n = r;
  else if constexpr (n == 4)
    r_2n = std::sqrt(r);
  else
    r_2n = std::cbrt(r * r);
  const double frob_sq = 2.0 / (n + 1) * sum_sq;
  return n * r_2n / frob_sq;
}

template <int Dim> double mean_ratio_t(const double *verts, double det) {
  return mean_ratio_of<Dim>(det, squared_edge_sum<Dim>(verts));
}

template <int Dim> double mean_ratio_t(const double *verts) {
  return mean_ratio_t<Dim>(verts, edge_determinant<Dim>(verts));
}

// Asks for the coordinates of cell c's vertices ahead of their use. The
// vertices of a refined mesh are scattered over the coordinates (new ones
// are appended), so a pass over the cells that gathers each cell's points
// misses the core's cache on every one; the passes call this kAhead (8)
// cells early.
template <int Dim> inline void prefetch_points(const Mesh &mesh, CellId c) {
  const VertexId *ids = mesh.cell(c);
  for (int i = 0; i <= Dim; ++i)
    __builtin_prefetch(mesh.point(ids[i]));
}

} // namespace bisect::geometry
