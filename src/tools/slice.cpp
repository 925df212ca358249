// Sections of 4D meshes by axis-aligned hyperplanes, and of 3D meshes by
// axis-aligned planes (2D+t meshes at a time t). Written for a pentatope; a
// tet is the same with four vertices (the sections are then triangles and
// quadrilaterals, and the pulling triangulation splits the quadrilaterals).
//
// Every pentatope is classified by the side of each vertex: -1 (x < value),
// 0 (on the hyperplane), +1. When both sides are present the hyperplane meets
// the interior and the section is a 3-polytope whose vertices ("cut points")
// are the on-plane vertices and one point per edge joining the two sides:
//   sides (-,0,+) = (1,0,4) or (4,0,1), (1,1,3), (2,2,1), (1,3,1) ...  tetrahedron
//                   (2,1,2)                                            square pyramid
//                   (2,0,3) or (3,0,2)                                 triangular prism
// A cut point is keyed by the sorted vertex-rank pair of its edge, (v, v)
// for a vertex v on the plane; keys are global, so neighbours share cut
// points. A vertex's rank is its place in the lexicographic order of the
// coordinates of the vertices of the cells that meet the plane: the section
// (its cells, and each cut point interpolated from the edge's lower-ranked
// end) depends on the mesh's cells alone, not on how its vertices are
// numbered, so a mesh gathered from MPI parts gives the serial run's.
//
// Each polytope is cut into tets by the pulling triangulation: take its
// smallest-key vertex v, triangulate recursively every facet not containing
// v, and cone those pieces from v. The pulling triangulation restricted to a
// face is the pulling triangulation of that face, which depends only on the
// face's own keys, so two pentatopes cut their shared quadrilateral the same
// way (by the diagonal through its smallest-key vertex). The faces of the
// section are the sections of the pentatope's faces, so the recursion runs on
// vertex subsets of the pentatope.
//
// A pentatope with one side empty meets the plane in the face spanned by its
// on-plane vertices; only a whole tetrahedral facet (4 on-plane vertices)
// matters, and it is produced by one of the (at most two) pentatopes sharing
// it: the one on the side x >= value when there is one.
#include "bisect/slice.hpp"

#include "bisect/measure.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace bisect {
namespace {

using Key = std::uint64_t; // (smaller rank << 32) | larger rank
using Tet = std::array<Key, 4>;

Key point_key(VertexId a, VertexId b) {
  if (b < a)
    std::swap(a, b);
  return (Key(a) << 32) | Key(b);
}
VertexId key_first(Key k) {
  return VertexId(k >> 32);
}
VertexId key_second(Key k) {
  return VertexId(k & 0xffffffffu);
}

// One cell (pentatope or tet): its vertices' ranks (kNoVertex for a cell
// that does not meet the plane) and the side of each vertex.
struct Pentatope {
  int n = 5; // vertices
  std::array<VertexId, 5> ids{};
  std::array<int, 5> side{};
  unsigned all() const { return (1u << n) - 1; }
};

bool crosses(const Pentatope &p, unsigned mask) {
  bool neg = false, pos = false;
  for (int i = 0; i < p.n; ++i)
    if (mask >> i & 1u)
      neg |= p.side[i]<0, pos |= p.side[i]> 0;
  return neg && pos;
}

// The vertices of the section of the face `mask` (a subset of the pentatope's
// vertices): the on-plane vertices and, when the face crosses the plane, one
// point per edge joining the two sides.
std::vector<Key> section_points(const Pentatope &p, unsigned mask) {
  std::vector<Key> out;
  for (int i = 0; i < p.n; ++i) {
    if (!(mask >> i & 1u))
      continue;
    if (p.side[i] == 0)
      out.push_back(point_key(p.ids[i], p.ids[i]));
    for (int j = i + 1; j < p.n; ++j)
      if ((mask >> j & 1u) && p.side[i] * p.side[j] < 0)
        out.push_back(point_key(p.ids[i], p.ids[j]));
  }
  return out;
}

// Dimension of the section of face `mask`: one less than the face when the
// plane crosses it, else that of the face spanned by its on-plane vertices.
int section_dim(const Pentatope &p, unsigned mask) {
  if (crosses(p, mask))
    return std::popcount(mask) - 2;
  int zeros = 0;
  for (int i = 0; i < p.n; ++i)
    zeros += (mask >> i & 1u) && p.side[i] == 0;
  return zeros - 1;
}

// Pulling triangulation of the k-dimensional section of face `mask` into
// k-simplices (k+1 keys each).
std::vector<std::vector<Key>> pulling(const Pentatope &p, unsigned mask, int k) {
  std::vector<Key> pts = section_points(p, mask);
  if (int(pts.size()) == k + 1)
    return {pts};
  const Key apex = *std::min_element(pts.begin(), pts.end());
  std::vector<std::vector<Key>> out, seen_facets;
  for (int u = 0; u < p.n; ++u) {
    if (!(mask >> u & 1u))
      continue;
    const unsigned sub = mask & ~(1u << u);
    if (section_dim(p, sub) != k - 1)
      continue; // not a facet of the section
    std::vector<Key> facet = section_points(p, sub);
    std::sort(facet.begin(), facet.end());
    if (std::binary_search(facet.begin(), facet.end(), apex))
      continue;
    // Two faces of the pentatope can have the same section (the on-plane face).
    if (std::find(seen_facets.begin(), seen_facets.end(), facet) != seen_facets.end())
      continue;
    seen_facets.push_back(facet);
    for (std::vector<Key> &piece : pulling(p, sub, k - 1)) {
      piece.insert(piece.begin(), apex);
      out.push_back(std::move(piece));
    }
  }
  return out;
}

// The ranks of the vertices of the cells that meet the plane (a vertex on
// it, or one on each side), and the vertex of each rank.
struct Ranks {
  std::vector<VertexId> of;     // per vertex of the mesh; kNoVertex when unranked
  std::vector<VertexId> vertex; // per rank
};

// Each vertex's coordinate along the axis, a vertex within 1e-6 of the
// axis extent of its cells from the plane put on it: a cut that close to a
// vertex made cut points a rounding error apart on the vertex's edges, and
// cells between them degenerate (the sample cylinder's vertices at t =
// 0.49999999999999872 cut at t = 0.5; a Kuhn hypercube cut at t = 1e-7).
std::vector<double> axis_coordinates(const Mesh &mesh, int axis, double value) {
  const std::size_t nv = mesh.num_vertices();
  std::vector<double> x(nv), extent(nv, 0.0);
  for (std::size_t v = 0; v < nv; ++v)
    x[v] = mesh.point(VertexId(v))[axis];
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    const VertexId *ids = mesh.cell(CellId(c));
    double lo = x[ids[0]], hi = lo;
    for (int i = 1; i <= mesh.dim; ++i) {
      lo = std::min(lo, x[ids[i]]);
      hi = std::max(hi, x[ids[i]]);
    }
    for (int i = 0; i <= mesh.dim; ++i)
      extent[ids[i]] = std::max(extent[ids[i]], hi - lo);
  }
  for (std::size_t v = 0; v < nv; ++v)
    if (x[v] != value && std::abs(x[v] - value) <= 1e-6 * extent[v])
      x[v] = value;
  return x;
}

bool meets(const Mesh &mesh, const std::vector<double> &at, CellId c, double value) {
  bool below = false, above = false;
  for (int i = 0; i <= mesh.dim; ++i) {
    const double x = at[mesh.cell(c)[i]];
    below |= x <= value;
    above |= x >= value;
  }
  return below && above;
}

Ranks rank_vertices(const Mesh &mesh, const std::vector<double> &at, double value) {
  Ranks r;
  r.of.assign(mesh.num_vertices(), kNoVertex);
  for (std::size_t c = 0; c < mesh.num_cells(); ++c)
    if (meets(mesh, at, CellId(c), value))
      for (int i = 0; i <= mesh.dim; ++i)
        if (r.of[mesh.cell(CellId(c))[i]] == kNoVertex) {
          r.of[mesh.cell(CellId(c))[i]] = 0;
          r.vertex.push_back(mesh.cell(CellId(c))[i]);
        }
  const int d = mesh.dim;
  std::sort(r.vertex.begin(), r.vertex.end(), [&](VertexId a, VertexId b) {
    const double *pa = mesh.point(a), *pb = mesh.point(b);
    for (int k = 0; k < d; ++k)
      if (pa[k] != pb[k])
        return pa[k] < pb[k];
    return a < b; // coincident vertices (not in a valid mesh)
  });
  for (std::size_t i = 0; i < r.vertex.size(); ++i)
    r.of[r.vertex[i]] = VertexId(i);
  return r;
}

Pentatope classify(const Mesh &mesh, const std::vector<double> &at, const Ranks &ranks, CellId c,
                   double value) {
  Pentatope p;
  p.n = mesh.dim + 1;
  for (int i = 0; i < p.n; ++i) {
    const VertexId v = mesh.cell(c)[i];
    p.ids[i] = ranks.of[v];
    const double x = at[v];
    p.side[i] = x > value ? 1 : x < value ? -1 : 0;
  }
  return p;
}

int count_side(const Pentatope &p, int s) {
  return int(std::count(p.side.begin(), p.side.begin() + p.n, s));
}

// For every facet lying in the plane, the cell that produces it: one on the
// side x >= value when there is one. (Facets of a tet mesh have 3 vertices;
// the unused fourth slot stays kNoVertex.)
std::map<std::array<VertexId, 4>, CellId>
in_plane_owners(const Mesh &mesh, const std::vector<double> &at, const Ranks &ranks, double value) {
  std::map<std::array<VertexId, 4>, CellId> owner;
  std::map<std::array<VertexId, 4>, bool> owner_above;
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    const Pentatope p = classify(mesh, at, ranks, CellId(c), value);
    if (count_side(p, 0) != p.n - 1)
      continue;
    std::array<VertexId, 4> facet{kNoVertex, kNoVertex, kNoVertex, kNoVertex};
    int n = 0;
    for (int i = 0; i < p.n; ++i)
      if (p.side[i] == 0)
        facet[n++] = p.ids[i];
    std::sort(facet.begin(), facet.end()); // unused entries are kNoVertex and stay last
    const bool above = count_side(p, 1) == 1;
    auto it = owner.find(facet);
    if (it == owner.end() || (above && !owner_above[facet])) {
      owner[facet] = CellId(c);
      owner_above[facet] = above;
    }
  }
  return owner;
}

// The section simplices of cell c (tets of a pentatope, triangles of a tet;
// a triangle's fourth key unused), as cut-point keys.
std::vector<Tet> cut_cell(const Mesh &mesh, const std::vector<double> &at, const Ranks &ranks,
                          CellId c, double value,
                          const std::map<std::array<VertexId, 4>, CellId> &owners) {
  const Pentatope p = classify(mesh, at, ranks, c, value);
  const int k = p.n - 2; // dimension of the section
  std::vector<Tet> tets;
  if (crosses(p, p.all())) {
    for (const std::vector<Key> &piece : pulling(p, p.all(), k)) {
      assert(int(piece.size()) == k + 1);
      Tet t{};
      std::copy(piece.begin(), piece.end(), t.begin());
      tets.push_back(t);
    }
  } else if (count_side(p, 0) == p.n - 1) {
    std::vector<Key> pts = section_points(p, p.all());
    std::array<VertexId, 4> facet{kNoVertex, kNoVertex, kNoVertex, kNoVertex};
    for (int i = 0; i <= k; ++i)
      facet[i] = key_first(pts[i]);
    std::sort(facet.begin(), facet.end()); // unused entries are kNoVertex and stay last
    if (owners.at(facet) == c) {
      Tet t{};
      std::copy(pts.begin(), pts.end(), t.begin());
      tets.push_back(t);
    }
  }
  return tets;
}

// Builds the output vertices on demand: coordinates and point data of a cut
// point, interpolated along its edge (computed once per key).
struct VertexMaker {
  const Mesh &in;
  const std::vector<double> &at; // axis_coordinates()
  const Ranks &ranks;
  Mesh &out;
  int axis;
  double value;
  std::unordered_map<Key, VertexId> ids;

  VertexId get(Key k) {
    auto [it, fresh] = ids.try_emplace(k, VertexId(ids.size()));
    if (fresh)
      add(k);
    return it->second;
  }

  void add(Key k) {
    const VertexId a = ranks.vertex[key_first(k)], b = ranks.vertex[key_second(k)];
    const double *pa = in.point(a), *pb = in.point(b);
    // Parameter along a -> b (a ranked below b) where x[axis] reaches the value.
    const double lambda = a == b ? 0.0 : (value - at[a]) / (at[b] - at[a]);
    for (int d = 0; d < in.dim; ++d)
      if (d != axis)
        out.coords.push_back(a == b ? pa[d] : pa[d] + lambda * (pb[d] - pa[d]));
    for (std::size_t n = 0; n < in.point_data.size(); ++n) {
      const DataArray &src = in.point_data[n];
      const bool label = is_label_array(src.name); // kept at a vertex, else kNoLabel
      for (int j = 0; j < src.components; ++j) {
        const double va = src.values[std::size_t(a) * src.components + j];
        const double vb = src.values[std::size_t(b) * src.components + j];
        out.point_data[n].values.push_back(a == b || lambda == 0 ? va
                                           : lambda == 1         ? vb
                                           : label               ? kNoLabel
                                                                 : (1 - lambda) * va + lambda * vb);
      }
    }
  }
};

// Appends simplex t (out.dim + 1 output ids), positively oriented.
void emit_tet(Mesh &out, std::array<VertexId, 4> t) {
  const int d = out.dim, nv = d + 1;
  double pts[12];
  for (int i = 0; i < nv; ++i)
    std::copy(out.point(t[i]), out.point(t[i]) + d, pts + d * i);
  if (signed_volume(pts, d) < 0)
    std::swap(t[nv - 2], t[nv - 1]);
  out.cells.insert(out.cells.end(), t.begin(), t.begin() + nv);
}

void copy_cell_data(const Mesh &in, const std::vector<CellId> &parent, Mesh &out) {
  for (const DataArray &src : in.cell_data) {
    if (src.name.rfind("bisect:", 0) == 0)
      continue; // bisection state of the 4D cells
    DataArray dst{src.name, src.components, {}};
    dst.values.reserve(parent.size() * src.components);
    for (CellId c : parent)
      for (int j = 0; j < src.components; ++j)
        dst.values.push_back(src.values[std::size_t(c) * src.components + j]);
    out.cell_data.push_back(std::move(dst));
  }
}

} // namespace

Mesh slice_mesh(const Mesh &mesh4, int axis, double value) {
  if (mesh4.dim != 4 && mesh4.dim != 3)
    throw InputError("",
                     "slice: needs a 3D or 4D mesh, got dimension " + std::to_string(mesh4.dim));
  if (axis < 0 || axis >= mesh4.dim)
    throw InputError("", "slice: axis must be 0.." + std::to_string(mesh4.dim - 1) + ", got " +
                             std::to_string(axis));

  Mesh out;
  out.dim = mesh4.dim - 1;
  for (const DataArray &a : mesh4.point_data)
    out.point_data.push_back({a.name, a.components, {}});

  const std::vector<double> at = axis_coordinates(mesh4, axis, value);
  const Ranks ranks = rank_vertices(mesh4, at, value);
  const auto owners = in_plane_owners(mesh4, at, ranks, value);
  VertexMaker maker{mesh4, at, ranks, out, axis, value, {}};
  std::vector<CellId> parent;
  for (std::size_t c = 0; c < mesh4.num_cells(); ++c) {
    for (const Tet &t : cut_cell(mesh4, at, ranks, CellId(c), value, owners)) {
      std::array<VertexId, 4> ids{kNoVertex, kNoVertex, kNoVertex, kNoVertex};
      for (int i = 0; i <= out.dim; ++i)
        ids[i] = maker.get(t[i]);
      emit_tet(out, ids);
      parent.push_back(CellId(c));
    }
  }
  copy_cell_data(mesh4, parent, out);
  // A section of a 3D mesh at z (or t) = value stays at that height, so it
  // overlays the mesh it was cut from (see kPlaneZArray).
  if (mesh4.dim == 3 && axis == 2 && value != 0 && out.num_vertices() > 0)
    out.point_data.push_back({kPlaneZArray, 1, std::vector<double>(out.num_vertices(), value)});
  return out;
}

} // namespace bisect
