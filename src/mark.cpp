// Marking (ALGORITHMS.md §2-4; seeds 002 and 000). Every mark is the
// consistent edge of some old sub-simplex in one global edge order, so
// neighbours always agree on the marks of a shared face.
#include "mark.hpp"

#include "measure.hpp"
#include "numbering.hpp"

#include <algorithm>
#include <cmath>

namespace bisect {

namespace {

double squared_length(const EdgeOrder &o, VertexId a, VertexId b) {
  if (a > b) std::swap(a, b);
  const double *p = o.coords->data() + std::size_t(a) * o.dim;
  const double *q = o.coords->data() + std::size_t(b) * o.dim;
  double s = 0;
  for (int k = 0; k < o.dim; ++k) {
    double d = q[k] - p[k];
    s += d * d;
  }
  return s;
}

} // namespace

bool EdgeOrder::before(VertexId a, VertexId b, VertexId c, VertexId d) const {
  if (a > b) std::swap(a, b);
  if (c > d) std::swap(c, d);
  if (marking == Marking::Longest) {
    double lab = squared_length(*this, a, b), lcd = squared_length(*this, c, d);
    if (lab != lcd) return lab > lcd;
  }
  return a != c ? a < c : b < d;
}

EdgeOrder edge_order(const Mesh &mesh) {
  return EdgeOrder{mesh.marking, &mesh.coords, mesh.dim};
}

EdgePick consistent_edge(const EdgeOrder &order, const VertexId *ids, int count) {
  EdgePick best{0, 1};
  for (int i = 0; i < count; ++i)
    for (int j = i + 1; j < count; ++j)
      if ((i || j != 1) &&
          order.before(ids[i], ids[j], ids[best.first], ids[best.second]))
        best = EdgePick{i, j};
  return best;
}

void triangle_tuple(const EdgeOrder &order, const VertexId *t, VertexId *out) {
  EdgePick e = consistent_edge(order, t, 3);
  int gamma = 3 - e.first - e.second;
  VertexId a = t[e.first], g = t[gamma], b = t[e.second];
  out[0] = a, out[1] = g, out[2] = b;
}

namespace {

// For a tet with refinement edge (a, b) = ids[ea], ids[eb]: the marks of the
// faces opposite a and b, as vertex pairs.
struct TetMarks {
  VertexId a, b;          // refinement edge
  VertexId m1[2], m2[2];  // marks of the faces opposite a and opposite b
  VertexId c, d;          // the two other vertices
};

TetMarks tet_marks(const EdgeOrder &order, const VertexId *ids) {
  EdgePick e = consistent_edge(order, ids, 4);
  TetMarks m{};
  m.a = ids[e.first];
  m.b = ids[e.second];
  int rest[2], r = 0;
  for (int i = 0; i < 4; ++i)
    if (i != e.first && i != e.second) rest[r++] = i;
  m.c = ids[rest[0]];
  m.d = ids[rest[1]];
  VertexId fa[3] = {m.b, m.c, m.d}, fb[3] = {m.a, m.c, m.d};
  EdgePick p = consistent_edge(order, fa, 3), q = consistent_edge(order, fb, 3);
  m.m1[0] = fa[p.first];
  m.m1[1] = fa[p.second];
  m.m2[0] = fb[q.first];
  m.m2[1] = fb[q.second];
  return m;
}

bool contains(const VertexId *e, VertexId v) { return e[0] == v || e[1] == v; }
VertexId other(const VertexId *e, VertexId v) { return e[0] == v ? e[1] : e[0]; }

} // namespace

TetType classify_tet(const EdgeOrder &order, const VertexId *ids) {
  TetMarks m = tet_marks(order, ids);
  bool t1 = contains(m.m1, m.b), t2 = contains(m.m2, m.a); // mark touches the refinement edge
  if (t1 && t2) return other(m.m1, m.b) == other(m.m2, m.a) ? TetType::Planar : TetType::Adjacent;
  if (t1 || t2) return TetType::Mixed;
  return TetType::Opposite;
}

void mark_mesh(Mesh &mesh, Marking marking) {
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  mesh.marking = marking;
  mesh.stage.assign(nc, Stage::Maubach);
  mesh.tag.assign(nc, std::uint8_t(2));
  EdgeOrder order = edge_order(mesh);
  for (std::size_t c = 0; c < nc; ++c) {
    VertexId *x = mesh.cell(CellId(c));
    if (marking == Marking::Sorted) {
      std::sort(x, x + nv);
      mesh.tag[c] = std::uint8_t(n);
    } else if (n == 2) {
      VertexId t[3] = {x[0], x[1], x[2]};
      triangle_tuple(order, t, x);
    } else if (n == 3) {
      TetMarks m = tet_marks(order, x);
      bool planar = contains(m.m1, m.b) && contains(m.m2, m.a) &&
                    other(m.m1, m.b) == other(m.m2, m.a);
      if (planar) { // Pu: refinement (a, b), marks (b, c), (a, c) -> (a, c, b, d)_2
        VertexId c3 = other(m.m1, m.b), d3 = (c3 == m.c) ? m.d : m.c;
        x[0] = m.a, x[1] = c3, x[2] = m.b, x[3] = d3;
      } else {
        mesh.stage[c] = Stage::Opposite;
        mesh.tag[c] = 0;
      }
    } else {
      mesh.stage[c] = Stage::Opposite;
      mesh.tag[c] = 0;
    }
  }
}

namespace {

int find_array(const std::vector<DataArray> &arrays, const char *name) {
  for (std::size_t i = 0; i < arrays.size(); ++i)
    if (arrays[i].name == name) return int(i);
  return -1;
}

void set_array(std::vector<DataArray> &arrays, DataArray a) {
  int i = find_array(arrays, a.name.c_str());
  if (i >= 0) arrays[i] = std::move(a);
  else arrays.push_back(std::move(a));
}

} // namespace

void encode_state(Mesh &mesh) {
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  DataArray order{kOrderArray, nv, std::vector<double>(nc * nv)};
  DataArray stage{kStageArray, 1, std::vector<double>(nc)};
  DataArray tag{kTagArray, 1, std::vector<double>(nc)};
  DataArray marking{kMarkingArray, 1, std::vector<double>(nc, double(int(mesh.marking)))};
  double pts[5 * 4];
  for (std::size_t c = 0; c < nc; ++c) {
    cell_points(mesh, CellId(c), pts);
    VertexId *x = mesh.cell(CellId(c));
    bool flip = signed_volume(pts, n) < 0;
    for (int i = 0; i < nv; ++i) order.values[c * nv + i] = i;
    if (flip) {
      std::swap(x[0], x[1]);
      order.values[c * nv + 0] = 1;
      order.values[c * nv + 1] = 0;
    }
    stage.values[c] = mesh.stage.empty() ? 0 : double(int(mesh.stage[c]));
    tag.values[c] = mesh.tag.empty() ? 0 : double(mesh.tag[c]);
  }
  if (mesh.marked()) {
    set_array(mesh.cell_data, std::move(order));
    set_array(mesh.cell_data, std::move(stage));
    set_array(mesh.cell_data, std::move(tag));
    set_array(mesh.cell_data, std::move(marking));
  }
}

bool decode_state(Mesh &mesh, const std::string &path) {
  int io = find_array(mesh.cell_data, kOrderArray), is = find_array(mesh.cell_data, kStageArray),
      it = find_array(mesh.cell_data, kTagArray), im = find_array(mesh.cell_data, kMarkingArray);
  int present = (io >= 0) + (is >= 0) + (it >= 0) + (im >= 0);
  if (present == 0) return false;
  if (present != 4)
    throw InputError(path, std::string("bisection state is incomplete: expected cell arrays ") +
                               kOrderArray + ", " + kStageArray + ", " + kTagArray + ", " +
                               kMarkingArray);
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  const DataArray &order = mesh.cell_data[io], &stage = mesh.cell_data[is],
                  &tag = mesh.cell_data[it], &marking = mesh.cell_data[im];
  if (order.components != nv || stage.components != 1 || tag.components != 1 ||
      marking.components != 1)
    throw InputError(path, "bisection state arrays have the wrong number of components");
  double m0 = nc ? marking.values[0] : 0;
  if (!(m0 == 0 || m0 == 1 || m0 == 2))
    throw InputError(path, std::string(kMarkingArray) + " must be 0, 1 or 2");
  mesh.marking = Marking(int(m0));
  mesh.stage.resize(nc);
  mesh.tag.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    auto bad = [&](const std::string &what) {
      return InputError(path, "cell " + std::to_string(c) + ": invalid bisection state (" +
                                  what + ")");
    };
    if (marking.values[c] != m0) throw bad("mixed " + std::string(kMarkingArray));
    double s = stage.values[c], t = tag.values[c];
    if (s == 1) {
      if (!(t >= 1 && t <= n && t == std::floor(t))) throw bad("Maubach tag out of range");
      mesh.stage[c] = Stage::Maubach;
    } else if (s == 0) {
      if (!(t >= 0 && t <= n - 3 && t == std::floor(t))) throw bad("Stage 1 generation out of range");
      mesh.stage[c] = Stage::Opposite;
    } else {
      throw bad("stage must be 0 or 1");
    }
    mesh.tag[c] = std::uint8_t(t);
    VertexId conn[5], *x = mesh.cell(CellId(c));
    std::copy(x, x + nv, conn);
    unsigned seen = 0;
    for (int i = 0; i < nv; ++i) {
      double p = order.values[c * nv + i];
      if (!(p >= 0 && p < nv && p == std::floor(p)) || (seen >> int(p) & 1u))
        throw bad(std::string(kOrderArray) + " is not a permutation");
      seen |= 1u << int(p);
      x[i] = conn[int(p)];
    }
  }
  for (int i : {io, is, it, im}) mesh.cell_data[i].name.clear();
  std::erase_if(mesh.cell_data, [](const DataArray &a) { return a.name.empty(); });
  return true;
}

std::optional<Marking> parse_marking(const std::string &name) {
  if (name == "index") return Marking::Index;
  if (name == "longest") return Marking::Longest;
  if (name == "sorted") return Marking::Sorted;
  return std::nullopt;
}

const char *marking_name(Marking marking) {
  switch (marking) {
  case Marking::Index: return "index";
  case Marking::Longest: return "longest";
  case Marking::Sorted: return "sorted";
  }
  return "?";
}

} // namespace bisect
