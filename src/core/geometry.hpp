// Small geometry on points of M coordinates, shared by the layers (one copy
// each; internal, header-only in core).
#pragma once

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

} // namespace bisect::geometry
