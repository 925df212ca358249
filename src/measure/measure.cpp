// Geometric measures of simplices and meshes (ALGORITHMS.md §7).
//
// Mean ratio: P. M. Knupp, "Algebraic mesh quality metrics", SIAM J. Sci.
// Comput. 23 (2001) 193-218. Kernels are templates on the dimension; the
// public functions dispatch once on `dim` (STYLE.md §3).
#include "bisect/measure.hpp"
#include "bisect/threads.hpp"
#include "core/dimension.hpp"
#include "core/geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <omp.h>

namespace bisect {
namespace {

using geometry::factorial;

using geometry::determinant;
using geometry::edge_determinant;
using geometry::mean_ratio_t;
using geometry::squared_distance;

template <int Dim> double signed_volume_t(const double *verts) {
  return edge_determinant<Dim>(verts) / factorial(Dim);
}

template <int Dim> void cell_points_t(const Mesh &mesh, CellId c, double *out) {
  const VertexId *cell = mesh.cell(c);
  for (int k = 0; k <= Dim; ++k) {
    const double *p = mesh.point(cell[k]);
    for (int i = 0; i < Dim; ++i)
      out[k * Dim + i] = p[i];
  }
}

// ---- similarity classes ----------------------------------------------------

constexpr int num_edges(int dim) {
  return dim * (dim + 1) / 2;
}

// Every permutation of the dim+1 vertices, as a map from key slot (edge (i,j),
// i<j, in lexicographic order) to the edge index of the unpermuted simplex.
template <int Dim> struct PermutationTable {
  static constexpr int kEdges = num_edges(Dim);
  std::vector<std::array<std::uint8_t, kEdges>> slots;
  PermutationTable() {
    std::array<int, Dim + 1> perm;
    for (int i = 0; i <= Dim; ++i)
      perm[i] = i;
    int edge_index[Dim + 1][Dim + 1] = {};
    for (int i = 0, e = 0; i <= Dim; ++i)
      for (int j = i + 1; j <= Dim; ++j, ++e)
        edge_index[i][j] = edge_index[j][i] = e;
    do {
      std::array<std::uint8_t, kEdges> s;
      for (int i = 0, e = 0; i <= Dim; ++i)
        for (int j = i + 1; j <= Dim; ++j, ++e)
          s[e] = std::uint8_t(edge_index[perm[i]][perm[j]]);
      slots.push_back(s);
    } while (std::next_permutation(perm.begin(), perm.end()));
  }
};

template <int Dim> const PermutationTable<Dim> &permutation_table() {
  static const PermutationTable<Dim> table;
  return table;
}

// Key of Dim-simplex: each squared edge length divided by their sum, rounded
// to 1e-6 (rounding is per edge, so it commutes with permuting); then the
// lexicographically smallest arrangement over all vertex permutations.
template <int Dim> void similarity_key_t(const double *verts, std::int32_t *key) {
  constexpr int E = num_edges(Dim);
  double len[E];
  double sum = 0;
  for (int i = 0, e = 0; i <= Dim; ++i)
    for (int j = i + 1; j <= Dim; ++j, ++e) {
      len[e] = squared_distance<Dim>(verts + i * Dim, verts + j * Dim);
      sum += len[e];
    }
  // Ratios of bisected simplices are rationals with power-of-two
  // denominators; on a decimal grid they can sit exactly halfway between two
  // steps, where rounding noise splits one class in two. An irrational grid
  // step (1e-6 / sqrt 2) keeps every such ratio away from the halfway points.
  constexpr double kScale = 1e6 * 1.4142135623730951;
  std::int32_t rounded[E];
  for (int e = 0; e < E; ++e)
    rounded[e] = sum > 0 ? std::int32_t(std::llround(len[e] / sum * kScale)) : 0;
  const auto &perms = permutation_table<Dim>().slots;
  const std::array<std::uint8_t, E> *best = &perms[0];
  for (const auto &p : perms) {
    for (int e = 0; e < E; ++e) {
      const std::int32_t a = rounded[p[e]], b = rounded[(*best)[e]];
      if (a < b) {
        best = &p;
        break;
      }
      if (a > b)
        break;
    }
  }
  for (int e = 0; e < E; ++e)
    key[e] = rounded[(*best)[e]];
}

template <int Dim> std::size_t count_similarity_classes_t(const Mesh &mesh) {
  constexpr int E = num_edges(Dim);
  const std::size_t nc = mesh.num_cells();
  std::vector<std::array<std::int32_t, E>> keys(nc);
  double pts[(Dim + 1) * Dim];
  for (std::size_t c = 0; c < nc; ++c) {
    cell_points_t<Dim>(mesh, CellId(c), pts);
    similarity_key_t<Dim>(pts, keys[c].data());
  }
  std::sort(keys.begin(), keys.end());
  return std::size_t(std::unique(keys.begin(), keys.end()) - keys.begin());
}

} // namespace

double determinant(const double *a, int n) {
  auto run = [&](auto dim) {
    constexpr int D = decltype(dim)::value;
    std::array<double, D * D> m;
    std::copy(a, a + D * D, m.begin());
    return determinant<D>(m);
  };
  switch (n) {
  case 1:
    return a[0];
  case 2:
    return run(std::integral_constant<int, 2>{});
  case 3:
    return run(std::integral_constant<int, 3>{});
  case 4:
    return run(std::integral_constant<int, 4>{});
  }
  return 0;
}

double signed_volume(const double *verts, int dim) {
  return dispatch(dim, [&]<int D>() { return signed_volume_t<D>(verts); });
}

double mean_ratio(const double *verts, int dim) {
  return dispatch(dim, [&]<int D>() { return mean_ratio_t<D>(verts); });
}

bool orient_positively(const Mesh &mesh, VertexId *ids) {
  double pts[5 * 4];
  for (int i = 0; i <= mesh.dim; ++i)
    std::copy(mesh.point(ids[i]), mesh.point(ids[i]) + mesh.dim, pts + i * mesh.dim);
  if (signed_volume(pts, mesh.dim) >= 0)
    return false;
  std::swap(ids[0], ids[1]);
  return true;
}

void cell_points(const Mesh &mesh, CellId c, double *out) {
  dispatch(mesh.dim, [&]<int D>() { cell_points_t<D>(mesh, c, out); });
}

// quality_summary is in check.cpp: the cell pass of the checks computes it.

QualityHistogram quality_histogram(const Mesh &mesh, int bins) {
  QualityHistogram out;
  out.summary = {1, 0, 0};
  out.counts.assign(std::size_t(std::max(bins, 1)), 0);
  const std::size_t nc = mesh.num_cells(), nb = out.counts.size();
  if (nc == 0)
    return out;
  // Blocks of cells, their sums added in block order; the counts are exact.
  constexpr std::size_t kBlock = std::size_t(1) << 14;
  const std::size_t blocks = (nc + kBlock - 1) / kBlock;
  std::vector<double> lo(blocks), hi(blocks), sum(blocks);
  const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
  std::vector<std::vector<std::size_t>> counts(std::size_t(workers),
                                               std::vector<std::size_t>(nb, 0));
#pragma omp parallel num_threads(workers)
  {
    std::vector<std::size_t> &mine = counts[std::size_t(omp_get_thread_num())];
    double pts[5 * 4];
#pragma omp for schedule(dynamic, 4)
    for (std::size_t k = 0; k < blocks; ++k) {
      double q_lo = 1, q_hi = 0, q_sum = 0;
      for (std::size_t c = k * kBlock; c < std::min(nc, (k + 1) * kBlock); ++c) {
        cell_points(mesh, CellId(c), pts);
        const double q = mean_ratio(pts, mesh.dim);
        q_lo = std::min(q_lo, q);
        q_hi = std::max(q_hi, q);
        q_sum += q;
        ++mine[std::min(std::size_t(q * double(nb)), nb - 1)];
      }
      lo[k] = q_lo, hi[k] = q_hi, sum[k] = q_sum;
    }
  }
  double total = 0;
  for (std::size_t k = 0; k < blocks; ++k) {
    out.summary.min = std::min(out.summary.min, lo[k]);
    out.summary.max = std::max(out.summary.max, hi[k]);
    total += sum[k];
  }
  out.summary.mean = total / double(nc);
  for (const std::vector<std::size_t> &c : counts)
    for (std::size_t b = 0; b < nb; ++b)
      out.counts[b] += c[b];
  return out;
}

std::vector<long long> similarity_key(const double *verts, int dim) {
  return dispatch(dim, [&]<int D>() {
    std::int32_t key[num_edges(D)];
    similarity_key_t<D>(verts, key);
    return std::vector<long long>(key, key + num_edges(D));
  });
}

std::size_t count_similarity_classes(const Mesh &mesh) {
  if (mesh.num_cells() == 0)
    return 0;
  return dispatch(mesh.dim, [&]<int D>() { return count_similarity_classes_t<D>(mesh); });
}

} // namespace bisect
