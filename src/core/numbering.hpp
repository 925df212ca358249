// The one place that owns local numbering and the tuple rules (STYLE.md §4).
//
// A cell of dimension n is a tuple of n+1 global vertex ids (x0, ..., xn)
// plus a Stage and a tag (mesh.hpp).
//
//   Local edges, lexicographic (n = 3):     x3
//     e0 = (0,1)  e3 = (1,2)                 /|.
//     e1 = (0,2)  e4 = (1,3)                / | .
//     e2 = (0,3)  e5 = (2,3)              x0--+--x2
//   (n = 2: 3 edges, n = 4: 10 edges)       . | /
//                                             x1
//   Facet k = the cell without local vertex k.         x1
//
// Maubach bisection of (x0..xn)_d, d in 1..n (ALGORITHMS.md §1):
//   z = midpoint(x0, xd),  d' = d - 1 if d > 1 else n
//   child 1 = (x0, ..., x(d-1), z, x(d+1), ..., xn)_d'
//   child 2 = (x1, ..., xd,     z, x(d+1), ..., xn)_d'
//
// Stage 1, "opposite the new vertex" (ALGORITHMS.md §3, §4): a cell in Stage
// Opposite with tag k stores its k new vertices first, newest first, then its
// old sub-simplex S (n+1-k vertices). Its refinement edge is the consistent
// edge (p, q) of S in the global edge order; with z the midpoint, the children
// are (z, new..., S \ p) and (z, new..., S \ q). A child whose old part is a
// triangle t becomes the Maubach tuple (alpha, gamma, beta, new...)_2, where
// (alpha, beta) is the consistent edge of t and gamma its third vertex:
//   2D: every triangle starts as (alpha, gamma, beta)_2 (newest vertex bisection)
//   3D: an A, M or O tet takes one Opposite step: (alpha, gamma, beta, v)_2
//   4D: every pentatope takes two:                 (alpha, gamma, beta, u, v)_2
#pragma once

#include "bisect/mesh.hpp"

#include <array>

namespace bisect {

template <int Dim> inline constexpr int kCellVertices = Dim + 1;
template <int Dim> inline constexpr int kCellEdges = Dim *(Dim + 1) / 2;

struct LocalEdge {
  int first, second; // local vertex indices, first < second
};

template <int Dim> constexpr std::array<LocalEdge, kCellEdges<Dim>> make_local_edges() {
  std::array<LocalEdge, kCellEdges<Dim>> edges{};
  int k = 0;
  for (int i = 0; i <= Dim; ++i)
    for (int j = i + 1; j <= Dim; ++j)
      edges[k++] = LocalEdge{i, j};
  return edges;
}
template <int Dim> inline constexpr auto kLocalEdges = make_local_edges<Dim>();

// The tag a Maubach child gets from a parent with tag d.
constexpr int maubach_child_tag(int d, int dim) {
  return d > 1 ? d - 1 : dim;
}

// Writes the two Maubach children of `x` (tag d) into c1 and c2.
template <int Dim>
inline void maubach_children(const VertexId *x, int d, VertexId z, VertexId *c1, VertexId *c2) {
  for (int i = 0; i <= Dim; ++i) {
    c1[i] = x[i];
    c2[i] = x[i];
  }
  c1[d] = z;
  for (int i = 0; i < d; ++i)
    c2[i] = x[i + 1];
  c2[d] = z;
}

} // namespace bisect
