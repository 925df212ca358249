// The bisection state in files: cell arrays bisect:* (README, "Files").
#include "bisect/state.hpp"

#include "bisect/mark.hpp"
#include "bisect/measure.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace bisect {

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
    if (mesh.marking == Marking::Explicit) {
      const int ne = nv * n / 2;
      DataArray rank{kEdgeRankArray, ne, std::vector<double>(nc * ne, -1.0)};
      for (std::size_t c = 0; c < nc; ++c) {
        const VertexId *x = mesh.cell(CellId(c));
        for (int i = 0, k = 0; i < nv; ++i)
          for (int j = i + 1; j < nv; ++j, ++k) {
            auto it = mesh.edge_rank.find(edge_key(x[i], x[j]));
            if (it != mesh.edge_rank.end()) rank.values[c * ne + k] = it->second;
          }
      }
      set_array(mesh.cell_data, std::move(rank));
    }
    encode_tree(mesh);
  }
}

void strip_state(Mesh &mesh) {
  const int order = find_array(mesh.cell_data, kOrderArray);
  if (order >= 0) {
    const DataArray &a = mesh.cell_data[std::size_t(order)];
    const std::size_t k = std::size_t(a.components);
    for (std::size_t c = 0; c < mesh.num_cells(); ++c)
      if (a.values[c * k] == 1) std::swap(mesh.cell(CellId(c))[0], mesh.cell(CellId(c))[1]);
  }
  std::erase_if(mesh.cell_data, [](const DataArray &a) {
    return a.name == kOrderArray || a.name == kStageArray || a.name == kTagArray ||
           a.name == kMarkingArray || a.name == kEdgeRankArray;
  });
  strip_tree(mesh);
}

bool decode_state(Mesh &mesh, const std::string &path) {
  int io = find_array(mesh.cell_data, kOrderArray), is = find_array(mesh.cell_data, kStageArray),
      it = find_array(mesh.cell_data, kTagArray), im = find_array(mesh.cell_data, kMarkingArray);
  int present = (io >= 0) + (is >= 0) + (it >= 0) + (im >= 0);
  if (present == 0) {
    strip_tree(mesh); // a tree without the state it belongs to means nothing
    return false;
  }
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
  if (!(m0 == 0 || m0 == 1 || m0 == 2 || m0 == 3))
    throw InputError(path, std::string(kMarkingArray) + " must be 0, 1, 2 or 3");
  mesh.marking = Marking(int(m0));
  int ir = find_array(mesh.cell_data, kEdgeRankArray);
  mesh.edge_rank.clear();
  if (mesh.marking == Marking::Explicit) {
    const int ne = nv * n / 2;
    if (ir < 0 || mesh.cell_data[ir].components != ne)
      throw InputError(path, std::string("explicit marking needs the cell array ") + kEdgeRankArray +
                                 " with " + std::to_string(ne) + " components");
    const DataArray &rank = mesh.cell_data[ir];
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = mesh.cell(CellId(c)); // stored connectivity, as encoded
      for (int i = 0, k = 0; i < nv; ++i)
        for (int j = i + 1; j < nv; ++j, ++k) {
          double r = rank.values[c * ne + k];
          if (r == -1) continue;
          if (!(r >= 0 && r < 4294967295.0 && r == std::floor(r)))
            throw InputError(path, "cell " + std::to_string(c) + ": " + kEdgeRankArray +
                                       " holds " + std::to_string(r) + ", not a rank");
          auto [it, fresh] = mesh.edge_rank.emplace(edge_key(x[i], x[j]), std::uint32_t(r));
          if (!fresh && it->second != std::uint32_t(r))
            throw InputError(path, "cell " + std::to_string(c) + ": " + kEdgeRankArray +
                                       " gives edge " + std::to_string(x[i]) + "-" +
                                       std::to_string(x[j]) + " two different ranks");
        }
    }
  }
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
      if (!(t >= 0 && t <= n - 3 && t == std::floor(t))) throw bad("Stage 1 tag (generation) out of range");
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
  if (std::string why = check_state_consistency(mesh); !why.empty())
    throw InputError(path, "the bisection state is inconsistent (" + why +
                               "): the file was not written by bisect as it is, or was altered "
                               "(cell order, connectivity or bisect:* arrays)");
  for (int i : {io, is, it, im, ir})
    if (i >= 0) mesh.cell_data[i].name.clear();
  std::erase_if(mesh.cell_data, [](const DataArray &a) { return a.name.empty(); });
  decode_tree(mesh, path);
  return true;
}

} // namespace bisect
