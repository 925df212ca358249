// Vertex colourings (seed 001 §2-3): propagation across facets, the check of
// a given colouring, and the barycentric subdivision that makes any mesh
// colourable.
//
// A proper (n+1)-colouring of an n-dimensional simplicial mesh is forced
// cell by cell across facets, so a facet-connected component has at most one
// up to renaming the colours. It has one exactly when the forcing never
// conflicts; for a simply connected manifold that is when every interior
// (n-2)-face (edge in 3D, vertex in 2D) lies in an even number of cells
// (M. Joswig, "Projectivities in simplicial complexes and colorings of simple
// polytopes", Math. Z. 240 (2002)).
#include "bisect/colour.hpp"

#include "bisect/mark.hpp"
#include "bisect/measure.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace bisect {

namespace {

constexpr std::uint64_t kNone = ~std::uint64_t(0);

// Open-addressing table from a sorted facet (Dim ids) to the (cell, local
// facet) that first showed it; the second owner pairs with it. Returns per
// cell corner (c * (Dim+1) + i, facet i = the cell without local vertex i)
// the corner of the neighbour across that facet, or kNone on the boundary.
// Sets `error` when a facet is shared by more than two cells.
template <int Dim>
std::vector<std::uint64_t> facet_neighbours(const Mesh &mesh, std::string &error) {
  constexpr int N = Dim + 1;
  using Key = std::array<VertexId, Dim>;
  const std::size_t nc = mesh.num_cells();
  std::size_t cap = 1024;
  while (cap < 2 * N * nc)
    cap *= 2;
  const std::size_t mask = cap - 1;
  constexpr std::uint64_t kEmpty = kNone, kPaired = kNone - 1;
  std::vector<Key> keys(cap);
  std::vector<std::uint64_t> owner(cap, kEmpty);
  std::vector<std::uint64_t> nb(N * nc, kNone);
  for (std::size_t c = 0; c < nc; ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    for (int i = 0; i < N; ++i) {
      Key k;
      for (int j = 0, m = 0; j < N; ++j)
        if (j != i)
          k[m++] = x[j];
      std::sort(k.begin(), k.end());
      std::uint64_t h = 0;
      for (VertexId v : k) {
        h = (h ^ v) * 0x9E3779B97F4A7C15ull;
        h ^= h >> 29;
      }
      const std::uint64_t corner = c * N + i;
      for (std::size_t s = h & mask;; s = (s + 1) & mask) {
        if (owner[s] == kEmpty) {
          keys[s] = k;
          owner[s] = corner;
          break;
        }
        if (keys[s] != k)
          continue;
        if (owner[s] == kPaired) {
          if (error.empty()) {
            error = "the facet {";
            for (int m = 0; m < Dim; ++m) {
              if (m)
                error += ',';
              error += std::to_string(k[m]);
            }
            error += "} is shared by more than two cells";
          }
        } else {
          nb[corner] = owner[s];
          nb[owner[s]] = corner;
          owner[s] = kPaired;
        }
        break;
      }
    }
  }
  return nb;
}

std::vector<std::uint64_t> neighbours(const Mesh &mesh, std::string &error) {
  if (mesh.dim == 2)
    return facet_neighbours<2>(mesh, error);
  if (mesh.dim == 3)
    return facet_neighbours<3>(mesh, error);
  throw std::invalid_argument("colouring needs a 2D or 3D mesh, not " + std::to_string(mesh.dim) +
                              "D");
}

// The usual obstruction near a conflict: an interior (n-2)-face of the
// component (no boundary facet contains it, so its cells form a closed ring)
// lying in an odd number of cells. Prefers one in a cell with `near`.
std::string odd_face_reason(const Mesh &mesh, const std::vector<std::uint64_t> &nb,
                            std::size_t start, VertexId near) {
  const int n = mesh.dim, N = n + 1;
  // The whole facet-connected component of `start`.
  std::vector<char> in(mesh.num_cells(), 0);
  std::vector<std::size_t> queue{start};
  in[start] = 1;
  for (std::size_t q = 0; q < queue.size(); ++q)
    for (int i = 0; i < N; ++i) {
      std::uint64_t across = nb[queue[q] * N + i];
      if (across != kNone && !in[across / N]) {
        in[across / N] = 1;
        queue.push_back(across / N);
      }
    }
  // key of the (n-2)-face: in 3D the edge's ids, in 2D the vertex id
  struct Ring {
    std::uint32_t cells = 0, boundary_facets = 0;
    bool near = false; // in a cell with `near`
  };
  std::unordered_map<std::uint64_t, Ring> ring;
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    if (!in[c])
      continue;
    const VertexId *x = mesh.cell(CellId(c));
    const bool has_near = std::find(x, x + N, near) != x + N;
    auto add = [&](std::uint64_t key) {
      Ring &r = ring[key];
      r.cells++;
      r.near |= has_near;
    };
    if (n == 3) {
      for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j)
          add(edge_key(x[i], x[j]));
    } else {
      for (int i = 0; i < N; ++i)
        add(x[i]);
    }
    for (int i = 0; i < N; ++i) {
      if (nb[c * N + i] != kNone)
        continue;
      VertexId f[3];
      for (int j = 0, m = 0; j < N; ++j)
        if (j != i)
          f[m++] = x[j];
      if (n == 3) {
        ring[edge_key(f[0], f[1])].boundary_facets++;
        ring[edge_key(f[0], f[2])].boundary_facets++;
        ring[edge_key(f[1], f[2])].boundary_facets++;
      } else {
        ring[f[0]].boundary_facets++;
        ring[f[1]].boundary_facets++;
      }
    }
  }
  std::uint64_t best = kNone;
  Ring best_ring;
  for (const auto &[key, r] : ring) {
    if (r.boundary_facets != 0 || r.cells % 2 == 0)
      continue;
    if (best == kNone || (r.near && !best_ring.near) || (r.near == best_ring.near && key < best)) {
      best = key;
      best_ring = r;
    }
  }
  if (best == kNone)
    return std::string("every interior ") + (n == 3 ? "edge" : "vertex") +
           " lies in an even number of cells, so the conflict comes from the domain's topology "
           "(a loop of cells that cannot be contracted)";
  const std::uint32_t best_count = best_ring.cells;
  const std::string face =
      n == 3 ? "edge " + std::to_string(best >> 32) + "-" + std::to_string(best & 0xffffffffu)
             : "vertex " + std::to_string(best);
  const std::string cells = std::to_string(best_count) + (n == 3 ? " tetrahedra" : " triangles");
  if (best_ring.near)
    return "interior " + face + " lies in " + cells + ", an odd number";
  return std::string("the mesh has interior ") + (n == 3 ? "edges" : "vertices") +
         " in an odd number of cells, e.g. " + face + " in " + cells;
}

// All permutations of 0..n, identity first.
std::vector<std::array<std::uint8_t, 4>> permutations(int n) {
  std::array<std::uint8_t, 4> p{0, 1, 2, 3};
  std::vector<std::array<std::uint8_t, 4>> all;
  do
    all.push_back(p);
  while (std::next_permutation(p.begin(), p.begin() + n + 1));
  return all;
}

// Reconciles components that share vertices: component k's colours are its
// local colours renamed by perm[k]. A depth-first search over the
// components of each vertex-connected group, the first one fixed. Returns
// an empty string on success.
std::string reconcile(const Mesh &mesh, const std::vector<std::uint32_t> &comp,
                      const std::vector<std::uint8_t> &corner, std::size_t ncomp,
                      std::vector<std::array<std::uint8_t, 4>> &perm) {
  const int N = mesh.dim + 1;
  const std::size_t nc = mesh.num_cells(), nv = mesh.num_vertices();
  // Vertices whose cells lie in more than one component.
  std::vector<std::uint32_t> first(nv, std::uint32_t(-1));
  std::vector<char> shared(nv, 0);
  for (std::size_t c = 0; c < nc; ++c)
    for (int i = 0; i < N; ++i) {
      VertexId v = mesh.cell(CellId(c))[i];
      if (first[v] == std::uint32_t(-1))
        first[v] = comp[c];
      else if (first[v] != comp[c])
        shared[v] = 1;
    }
  struct Use {
    std::uint32_t comp;
    VertexId v;
    std::uint8_t local;
    bool operator<(const Use &o) const { return comp != o.comp ? comp < o.comp : v < o.v; }
    bool operator==(const Use &o) const { return comp == o.comp && v == o.v; }
  };
  std::vector<Use> uses;
  for (std::size_t c = 0; c < nc; ++c)
    for (int i = 0; i < N; ++i) {
      VertexId v = mesh.cell(CellId(c))[i];
      if (shared[v])
        uses.push_back(Use{comp[c], v, corner[c * N + i]});
    }
  std::sort(uses.begin(), uses.end());
  uses.erase(std::unique(uses.begin(), uses.end()), uses.end());
  if (uses.empty())
    return {};
  // Constraints per component, and components per shared vertex.
  std::vector<std::size_t> begin(ncomp + 1, 0);
  for (const Use &u : uses)
    begin[u.comp + 1]++;
  std::partial_sum(begin.begin(), begin.end(), begin.begin());
  std::unordered_map<VertexId, std::vector<std::uint32_t>> comps_of;
  for (const Use &u : uses)
    comps_of[u.v].push_back(u.comp);

  const auto all = permutations(mesh.dim);
  std::unordered_map<VertexId, std::uint8_t> global;
  std::vector<char> placed(ncomp, 0);
  long steps = 0;
  const long kMaxSteps = 2000000;
  for (std::size_t start = 0; start < ncomp; ++start) {
    if (placed[start] || begin[start] == begin[start + 1])
      continue;
    // The group: components reachable through shared vertices, in BFS order.
    std::vector<std::uint32_t> group{std::uint32_t(start)};
    placed[start] = 1;
    for (std::size_t g = 0; g < group.size(); ++g)
      for (std::size_t u = begin[group[g]]; u < begin[group[g] + 1]; ++u)
        for (std::uint32_t other : comps_of[uses[u].v])
          if (!placed[other]) {
            placed[other] = 1;
            group.push_back(other);
          }
    // Depth-first search; choice[g] indexes `all`; trail undoes assignments.
    std::vector<std::size_t> choice(group.size(), 0);
    std::vector<std::vector<VertexId>> trail(group.size());
    std::size_t g = 0;
    while (true) {
      if (++steps > kMaxSteps)
        return "the pieces that touch only at vertices or edges could not be reconciled within " +
               std::to_string(kMaxSteps) + " search steps";
      const std::uint32_t k = group[g];
      bool fits = false;
      // The first component of a group is fixed: renaming all colours is free.
      const std::size_t limit = g == 0 ? 1 : all.size();
      for (; choice[g] < limit; ++choice[g]) {
        const auto &p = all[choice[g]];
        fits = true;
        for (std::size_t u = begin[k]; u < begin[k + 1] && fits; ++u) {
          auto it = global.find(uses[u].v);
          fits = it == global.end() || it->second == p[uses[u].local];
        }
        if (fits)
          break;
      }
      if (fits) {
        const auto &p = all[choice[g]];
        perm[k] = p;
        for (std::size_t u = begin[k]; u < begin[k + 1]; ++u)
          if (global.emplace(uses[u].v, p[uses[u].local]).second)
            trail[g].push_back(uses[u].v);
        if (++g == group.size())
          break;
        choice[g] = 0;
        continue;
      }
      if (g == 0) {
        VertexId v = uses[begin[group[0]]].v;
        return "the pieces of the mesh that touch only at vertices or edges (e.g. at vertex " +
               std::to_string(v) + ") cannot agree on colours";
      }
      --g; // backtrack
      for (VertexId v : trail[g])
        global.erase(v);
      trail[g].clear();
      ++choice[g];
    }
  }
  return {};
}

} // namespace

Colouring colour_mesh(const Mesh &mesh) {
  Colouring out;
  std::string error;
  const std::vector<std::uint64_t> nb = neighbours(mesh, error);
  if (!error.empty()) {
    out.why = error;
    return out;
  }
  const int n = mesh.dim, N = n + 1;
  const std::size_t nc = mesh.num_cells(), nv = mesh.num_vertices();
  const std::uint32_t kNoComp = std::uint32_t(-1);
  std::vector<std::uint32_t> comp(nc, kNoComp), stamp(nv, kNoComp);
  std::vector<std::uint8_t> vcol(nv, 0), corner(N * nc, 0);
  std::vector<std::size_t> queue;
  const int colour_sum = n * (n + 1) / 2;
  std::uint32_t k = 0;
  for (std::size_t seed = 0; seed < nc; ++seed) {
    if (comp[seed] != kNoComp)
      continue;
    k = std::uint32_t(out.components++);
    const VertexId *s = mesh.cell(CellId(seed));
    for (int i = 0; i < N; ++i) {
      vcol[s[i]] = std::uint8_t(i);
      stamp[s[i]] = k;
      corner[seed * N + i] = std::uint8_t(i);
    }
    comp[seed] = k;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::size_t c = queue[q];
      const VertexId *x = mesh.cell(CellId(c));
      for (int i = 0; i < N; ++i) {
        const std::uint64_t across = nb[c * N + i];
        if (across == kNone)
          continue;
        const std::size_t d = across / N;
        if (comp[d] != kNoComp)
          continue;
        const VertexId v = mesh.cell(CellId(d))[across % N];
        int missing = colour_sum;
        for (int j = 0; j < N; ++j)
          if (j != i)
            missing -= vcol[x[j]];
        if (stamp[v] == k && vcol[v] != missing) {
          out.why = "vertex " + std::to_string(v) + " would need colours " +
                    std::to_string(std::min<int>(vcol[v], missing)) + " and " +
                    std::to_string(std::max<int>(vcol[v], missing)) + " (" +
                    odd_face_reason(mesh, nb, d, v) + ")";
          return out;
        }
        vcol[v] = std::uint8_t(missing);
        stamp[v] = k;
        comp[d] = k;
        const VertexId *y = mesh.cell(CellId(d));
        for (int j = 0; j < N; ++j)
          corner[d * N + j] = vcol[y[j]];
        queue.push_back(d);
      }
    }
  }
  std::vector<std::array<std::uint8_t, 4>> perm(out.components,
                                                std::array<std::uint8_t, 4>{0, 1, 2, 3});
  if (out.components > 1) {
    out.why = reconcile(mesh, comp, corner, out.components, perm);
    if (!out.why.empty())
      return out;
  }
  out.colour.assign(nv, 0);
  for (std::size_t c = 0; c < nc; ++c)
    for (int i = 0; i < N; ++i)
      out.colour[mesh.cell(CellId(c))[i]] = perm[comp[c]][corner[c * N + i]];
  out.ok = true;
  return out;
}

std::string check_colouring(const Mesh &mesh, const std::vector<std::uint8_t> &colour) {
  const int N = mesh.dim + 1;
  if (colour.size() != mesh.num_vertices())
    return "the colouring has " + std::to_string(colour.size()) + " values for " +
           std::to_string(mesh.num_vertices()) + " vertices";
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    unsigned seen = 0;
    for (int i = 0; i < N; ++i) {
      const int col = colour[x[i]];
      if (col > mesh.dim)
        return "vertex " + std::to_string(x[i]) + " has colour " + std::to_string(col) +
               ", outside 0.." + std::to_string(mesh.dim);
      if (seen >> col & 1u) {
        VertexId other = x[0];
        for (int j = 0; j < i; ++j)
          if (colour[x[j]] == col)
            other = x[j];
        return "cell " + std::to_string(c) + " has two vertices (" + std::to_string(other) +
               " and " + std::to_string(x[i]) + ") of colour " + std::to_string(col);
      }
      seen |= 1u << col;
    }
  }
  return {};
}

std::optional<std::vector<std::uint8_t>> colour_array(const Mesh &mesh) {
  for (const DataArray &a : mesh.point_data) {
    if (a.name != kColourArray)
      continue;
    if (a.components != 1)
      throw InputError("", std::string("point array ") + kColourArray +
                               " must have 1 component, not " + std::to_string(a.components));
    std::vector<std::uint8_t> colour(mesh.num_vertices());
    for (std::size_t v = 0; v < colour.size() && v < a.values.size(); ++v)
      if (a.values[v] == kNoLabel)
        return std::nullopt; // vertices made by refinement after colouring: no colouring
    for (std::size_t v = 0; v < colour.size() && v < a.values.size(); ++v) {
      double c = a.values[v];
      if (!(c >= 0 && c <= mesh.dim && c == std::floor(c)))
        throw InputError("", std::string("point array ") + kColourArray + ": vertex " +
                                 std::to_string(v) + " has colour " + std::to_string(c) +
                                 ", expected a whole number 0.." + std::to_string(mesh.dim));
      colour[v] = std::uint8_t(c);
    }
    return colour;
  }
  return std::nullopt;
}

void set_colour_array(Mesh &mesh, const std::vector<std::uint8_t> &colour) {
  DataArray a{kColourArray, 1, std::vector<double>(colour.begin(), colour.end())};
  for (DataArray &b : mesh.point_data)
    if (b.name == kColourArray) {
      b = std::move(a);
      return;
    }
  mesh.point_data.push_back(std::move(a));
}

Mesh barycentric_subdivision(const Mesh &mesh, std::vector<std::uint8_t> *colour_out) {
  const int n = mesh.dim, N = n + 1;
  if (n != 2 && n != 3)
    throw std::invalid_argument("barycentric subdivision needs a 2D or 3D mesh, not " +
                                std::to_string(n) + "D");
  const std::size_t nc = mesh.num_cells(), nv = mesh.num_vertices();
  std::string error;
  const std::vector<std::uint64_t> nb = neighbours(mesh, error);
  if (!error.empty())
    throw InputError("", error);

  Mesh out;
  out.dim = n;
  out.coords = mesh.coords;
  std::vector<std::uint8_t> colour(nv, 0);
  // Point data rows are built alongside the coordinates: a centre is the mean
  // of its simplex's vertices, coordinates and point data alike.
  std::vector<DataArray> pdata;
  for (const DataArray &a : mesh.point_data)
    if (a.name != kColourArray)
      pdata.push_back(a);
  auto add_centre = [&](const VertexId *ids, int count, std::uint8_t kind) {
    VertexId id = VertexId(out.num_vertices());
    for (int k = 0; k < n; ++k) {
      double s = 0;
      for (int i = 0; i < count; ++i)
        s += mesh.point(ids[i])[k];
      out.coords.push_back(s / count);
    }
    for (DataArray &a : pdata)
      for (int k = 0; k < a.components; ++k) {
        double s = 0;
        for (int i = 0; i < count; ++i)
          s += a.values[std::size_t(ids[i]) * a.components + k];
        a.values.push_back(s / count);
      }
    colour.push_back(kind);
    return id;
  };

  // Edge centres (kind 1), shared through a map on the edge key.
  std::unordered_map<std::uint64_t, VertexId> edge_centre;
  edge_centre.reserve(nc * 2);
  std::vector<VertexId> cell_edges(nc * N * N, kNoVertex); // [c][i][j]
  for (std::size_t c = 0; c < nc; ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    for (int i = 0; i < N; ++i)
      for (int j = i + 1; j < N; ++j) {
        auto [it, fresh] = edge_centre.emplace(edge_key(x[i], x[j]), kNoVertex);
        if (fresh) {
          VertexId e[2] = {x[i], x[j]};
          it->second = add_centre(e, 2, 1);
        }
        cell_edges[(c * N + i) * N + j] = cell_edges[(c * N + j) * N + i] = it->second;
      }
  }
  // Face centres (3D, kind 2), shared with the neighbour across the facet.
  std::vector<VertexId> facet_centre(n == 3 ? nc * N : 0, kNoVertex);
  if (n == 3)
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = mesh.cell(CellId(c));
      for (int i = 0; i < N; ++i) {
        if (facet_centre[c * N + i] != kNoVertex)
          continue;
        VertexId f[3];
        for (int j = 0, m = 0; j < N; ++j)
          if (j != i)
            f[m++] = x[j];
        VertexId id = add_centre(f, 3, 2);
        facet_centre[c * N + i] = id;
        if (nb[c * N + i] != kNone)
          facet_centre[nb[c * N + i]] = id;
      }
    }
  // Cell centres (kind n), then the sub-cells, one per ordering of the vertices.
  std::vector<VertexId> centre(nc);
  for (std::size_t c = 0; c < nc; ++c)
    centre[c] = add_centre(mesh.cell(CellId(c)), N, std::uint8_t(n));
  std::array<int, 4> p{0, 1, 2, 3};
  std::vector<std::array<int, 4>> orders;
  do
    orders.push_back(p);
  while (std::next_permutation(p.begin(), p.begin() + N));
  out.cells.reserve(nc * orders.size() * N);
  for (std::size_t c = 0; c < nc; ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    for (const auto &o : orders) {
      VertexId sub[4];
      sub[0] = x[o[0]];
      sub[1] = cell_edges[(c * N + o[0]) * N + o[1]];
      if (n == 3)
        sub[2] = facet_centre[c * N + o[3]]; // the face {o0, o1, o2} is opposite o3
      sub[n] = centre[c];
      orient_positively(out, sub);
      out.cells.insert(out.cells.end(), sub, sub + N);
    }
  }
  out.point_data = std::move(pdata);
  for (const DataArray &a : mesh.cell_data) {
    if (a.name.rfind("bisect:", 0) == 0)
      continue;
    DataArray b{a.name, a.components, {}};
    b.values.reserve(a.values.size() * orders.size());
    for (std::size_t c = 0; c < nc; ++c)
      for (std::size_t s = 0; s < orders.size(); ++s)
        b.values.insert(b.values.end(), a.values.begin() + c * a.components,
                        a.values.begin() + (c + 1) * a.components);
    out.cell_data.push_back(std::move(b));
  }
  set_colour_array(out, colour);
  if (colour_out)
    *colour_out = std::move(colour);
  return out;
}

} // namespace bisect
