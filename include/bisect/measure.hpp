// Geometric measures of simplices and meshes (ALGORITHMS.md §7).
#pragma once

#include "bisect/mesh.hpp"

#include <cstddef>
#include <vector>

namespace bisect {

// Determinant of an n x n row-major matrix, n in 1..4.
double determinant(const double *a, int n);

// Signed n-volume of the simplex (x0..xn): det[x1-x0, ..., xn-x0] / n!.
// `verts` holds dim+1 points of dim coordinates each.
double signed_volume(const double *verts, int dim);

// Knupp's algebraic mean ratio: q = n |det S|^(2/n) / |S|_F^2 with S = A W^-1,
// A the edge matrix and W that of the equilateral reference simplex. 1 for
// the equilateral simplex, 0 for a degenerate one.
double mean_ratio(const double *verts, int dim);

// Orients the simplex of `mesh`'s vertices `ids` (dim+1 of them, in the
// mesh's cells or not) positively: swaps ids[0] and ids[1] when its signed
// volume is negative, and returns whether it did. The one copy of this rule.
bool orient_positively(const Mesh &mesh, VertexId *ids);

// Copies the coordinates of cell c into out[(dim+1)*dim].
void cell_points(const Mesh &mesh, CellId c, double *out);

struct QualitySummary {
  double min = 0, max = 0, mean = 0;
};
QualitySummary quality_summary(const Mesh &mesh);

// The mean ratio's min, max and mean over the cells (min 1, max 0 and mean
// 0 without cells) and its histogram of `bins` equal bins over [0, 1] (the
// last closed; bins >= 1), by all threads, the same for every count: what
// `bisect quality` prints.
struct QualityHistogram {
  QualitySummary summary;
  std::vector<std::size_t> counts;
};
QualityHistogram quality_histogram(const Mesh &mesh, int bins);

// Canonical similarity key: over all vertex permutations, the vector of
// squared edge lengths divided by their sum, lexicographically smallest,
// rounded to a relative 1e-6 grid. Two cells are similar iff keys are equal.
std::vector<long long> similarity_key(const double *verts, int dim);
std::size_t count_similarity_classes(const Mesh &mesh);

} // namespace bisect
