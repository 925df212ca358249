// Reading a .pvtu (VTK's parallel unstructured grid: a small XML file naming
// one .vtu piece per part) as one mesh: what `mpirun … bisect refine -o
// X.pvtu` writes, or ParaView. The pieces are read as .vtu files and merged:
// points shared by pieces become one vertex (by the bisect:global_id point
// array where the pieces carry it, else by their coordinates, which are the
// same bits in every piece that holds the point).
#include "bisect/io.hpp"
#include "bisect/state.hpp"
#include "core/arrays.hpp"
#include "core/faces.hpp"
#include "core/heights.hpp"
#include "core/reorder.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <regex>
#include <sstream>

namespace fs = std::filesystem;

namespace bisect {

namespace {

std::string pvtu_text(const std::string &path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec)
    throw InputError(path, "cannot open: " + ec.message());
  if (size > (std::uintmax_t(64) << 20))
    throw InputError(path, "larger than 64 MB: not a .pvtu index of pieces");
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  std::string xml = text.str();
  if (xml.find("PUnstructuredGrid") == std::string::npos)
    throw InputError(path, "not a parallel unstructured grid (no <PUnstructuredGrid>)");
  return xml;
}

std::vector<std::string> piece_sources(const std::string &path) {
  const std::string xml = pvtu_text(path);
  static const std::regex piece(R"re(<Piece\s+Source\s*=\s*"([^"]*)")re");
  std::vector<std::string> sources;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), piece); it != std::sregex_iterator();
       ++it) {
    const fs::path source((*it)[1].str());
    if (source.empty())
      throw InputError(path, "a <Piece> with an empty Source");
    sources.push_back(source.is_absolute()
                          ? source.string()
                          : (fs::path(path).parent_path() / source).lexically_normal().string());
    // Pieces are .vtu files, checked as inputs are when read (a regular,
    // readable, non-empty file: never a device, a FIFO or another .pvtu).
    std::string ext = source.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".vtu")
      throw InputError(path, "piece " + sources.back() + " is not a .vtu file");
  }
  if (sources.empty())
    throw InputError(path, "no <Piece Source=...> in the file");
  return sources;
}

const DataArray *find_array(const std::vector<DataArray> &arrays, const char *name) {
  for (const DataArray &a : arrays)
    if (a.name == name)
      return &a;
  return nullptr;
}

// The tree of merged pieces (write_pvtu, state.hpp): the parents named by
// coordinates become vertex ids, and the vertices after the first `fixed`
// (those without a global id, made since the run started) are ordered by
// level, then after their parents, then as they are, so that parents have
// the smaller ids the tree's arrays ask for. Adds the tree's arrays and
// drops the piece arrays; decode_tree then checks the tree as for a .vtu.
void tree_from_pieces(Mesh &out, std::size_t fixed, const std::string &path) {
  const DataArray *gen = find_array(out.cell_data, kPieceGenerationArray);
  const DataArray *lev = find_array(out.point_data, kPieceLevelArray);
  const DataArray *par = find_array(out.point_data, kPieceParentsArray);
  if (!gen && !lev && !par)
    return;
  const int dim = out.dim;
  if (!gen || !lev || !par)
    throw InputError(path, std::string("the pieces' tree is incomplete: ") + kPieceGenerationArray +
                               ", " + kPieceLevelArray + " and " + kPieceParentsArray +
                               " come together");
  for (const auto &[array, want] : {std::pair{gen, 1}, std::pair{lev, 1}, std::pair{par, 2 * dim}})
    if (array->components != want)
      throw InputError(path, array->name + " has " + std::to_string(array->components) +
                                 " components, not " + std::to_string(want));
  const std::size_t nv = out.num_vertices();
  // Vertices by coordinates, to find each parent.
  std::vector<VertexId> by_point(nv);
  std::iota(by_point.begin(), by_point.end(), VertexId(0));
  auto less = [&](const double *x, const double *y) {
    return std::lexicographical_compare(x, x + dim, y, y + dim);
  };
  std::sort(by_point.begin(), by_point.end(),
            [&](VertexId a, VertexId b) { return less(out.point(a), out.point(b)); });
  auto find = [&](const double *x) -> VertexId {
    auto it = std::lower_bound(by_point.begin(), by_point.end(), x,
                               [&](VertexId a, const double *y) { return less(out.point(a), y); });
    if (it == by_point.end() || !std::equal(x, x + dim, out.point(*it)))
      return kNoVertex;
    return *it;
  };
  std::vector<VertexId> parent(2 * nv, kNoVertex);
  std::vector<double> level(nv, 0.0);
  for (std::size_t v = 0; v < nv; ++v) {
    const double *p = par->values.data() + v * 2 * std::size_t(dim);
    level[v] = lev->values[v];
    const bool self_a = std::equal(p, p + dim, out.point(VertexId(v))),
               self_b = std::equal(p + dim, p + 2 * dim, out.point(VertexId(v)));
    if (self_a && self_b)
      continue; // an original vertex
    if (self_a || self_b)
      throw InputError(path, "point " + std::to_string(v) +
                                 " of the merged pieces: " + kPieceParentsArray +
                                 " names the point itself as one end of its parent edge");
    for (int k = 0; k < 2; ++k) {
      parent[2 * v + std::size_t(k)] = find(p + k * dim);
      if (parent[2 * v + std::size_t(k)] == kNoVertex) {
        std::ostringstream where;
        where.precision(17);
        for (int i = 0; i < dim; ++i)
          where << (i ? ", " : "(") << p[k * dim + i];
        throw InputError(
            path, "point " + std::to_string(v) + " of the merged pieces: " + kPieceParentsArray +
                      " names an end of its parent edge, " + where.str() + "), that no piece has");
      }
    }
  }
  // The new order of the vertices after `fixed`: by level, then by height
  // (0 when no parent of the same level follows `fixed`, else one more than
  // the highest such parent), then as they are.
  HeightProblem problem;
  const std::vector<int> height = parent_heights(parent, level, fixed, true, problem);
  if (problem == HeightProblem::Cycle)
    throw InputError(path, "the pieces' tree has a cycle (a vertex is its own ancestor)");
  if (problem == HeightProblem::ParentNewer)
    throw InputError(path,
                     std::string(kPieceLevelArray) +
                         ": a point is the midpoint of an edge with an end of a higher level");
  std::vector<VertexId> order(nv);
  std::iota(order.begin(), order.end(), VertexId(0));
  std::stable_sort(order.begin() + std::ptrdiff_t(fixed), order.end(), [&](VertexId a, VertexId b) {
    return level[a] != level[b] ? level[a] < level[b] : height[a] < height[b];
  });
  const std::vector<VertexId> id = reorder_vertices(out, order);
  // The tree's arrays (state.hpp), the piece arrays dropped.
  DataArray pa{kParentAArray, 1, std::vector<double>(nv, -1.0), ValueType::Int32};
  DataArray pb{kParentBArray, 1, std::vector<double>(nv, -1.0), ValueType::Int32};
  DataArray lv{kLevelArray, 1, std::vector<double>(nv, 0.0), ValueType::UInt16};
  for (std::size_t i = 0; i < nv; ++i) {
    const VertexId v = order[i];
    lv.values[i] = level[v];
    if (parent[2 * std::size_t(v)] == kNoVertex)
      continue;
    VertexId a = id[parent[2 * std::size_t(v)]], b = id[parent[2 * std::size_t(v) + 1]];
    if (a > b)
      std::swap(a, b);
    pa.values[i] = double(a);
    pb.values[i] = double(b);
  }
  DataArray generation{kGenerationArray, 1, gen->values, ValueType::UInt16};
  auto piece_array = [](const DataArray &a) {
    return a.name == kPieceGenerationArray || a.name == kPieceLevelArray ||
           a.name == kPieceParentsArray;
  };
  std::erase_if(out.point_data, piece_array);
  std::erase_if(out.cell_data, piece_array);
  out.cell_data.push_back(std::move(generation));
  out.point_data.push_back(std::move(pa));
  out.point_data.push_back(std::move(pb));
  out.point_data.push_back(std::move(lv));
}

} // namespace

std::vector<std::string> pvtu_pieces(const std::string &path) {
  return piece_sources(path);
}

std::vector<std::string> pvtu_point_arrays(const std::string &path) {
  const std::string xml = pvtu_text(path);
  std::vector<std::string> names;
  const std::size_t open = xml.find("<PPointData"), close = xml.find("</PPointData>");
  if (open == std::string::npos || close == std::string::npos || close < open)
    return names;
  const std::string section = xml.substr(open, close - open);
  static const std::regex array(R"re(<PDataArray[^>]*\sName\s*=\s*"([^"]*)")re");
  for (auto it = std::sregex_iterator(section.begin(), section.end(), array);
       it != std::sregex_iterator(); ++it)
    names.push_back((*it)[1].str());
  return names;
}

Mesh read_pvtu(const std::string &path) {
  const std::vector<std::string> sources = piece_sources(path);
  std::vector<Mesh> pieces;
  for (const std::string &source : sources) {
    try {
      pieces.push_back(read_mesh(source));
    } catch (const InputError &e) {
      throw InputError(path, std::string("piece ") + e.what());
    }
  }
  // A piece's own tree arrays (state.hpp) would name its own points: they
  // mean nothing once the pieces are merged (a .pvtu's tree is in the
  // bisect:piece_* arrays, see tree_from_pieces).
  for (Mesh &m : pieces) {
    auto tree = [](const DataArray &a) {
      return a.name == kGenerationArray || a.name == kParentAArray || a.name == kParentBArray ||
             a.name == kLevelArray || a.name == kParentRankArray;
    };
    std::erase_if(m.point_data, tree);
    std::erase_if(m.cell_data, tree);
  }
  const Mesh &first = pieces[0];
  const int dim = first.dim, n = first.cell_size();
  for (std::size_t p = 1; p < pieces.size(); ++p) {
    const Mesh &m = pieces[p];
    if (m.dim != dim)
      throw InputError(path, "piece " + sources[p] + " is " + std::to_string(m.dim) +
                                 "D, the first piece " + std::to_string(dim) + "D");
    if (!same_arrays(m.point_data, first.point_data) || !same_arrays(m.cell_data, first.cell_data))
      throw InputError(path, "piece " + sources[p] +
                                 " has other point or cell arrays than the first piece");
  }
  // Global ids: where every piece has the array, ids >= 0 name the same
  // vertex across pieces (and give their order); -1 is a vertex made by
  // refinement, found by its coordinates.
  auto gid_slot = [](const Mesh &m) -> int {
    for (std::size_t a = 0; a < m.point_data.size(); ++a)
      if (m.point_data[a].name == kGlobalIdArray && m.point_data[a].components == 1)
        return int(a);
    return -1;
  };
  const int gid = gid_slot(first);
  // Every piece vertex -> (key): gid vertices by id, the others by point.
  std::map<double, VertexId> by_id;
  std::map<std::vector<double>, VertexId> by_point;
  struct Ref {
    std::size_t piece;
    VertexId v;
  };
  std::vector<Ref> id_refs, point_refs;
  std::vector<std::vector<VertexId>> merged(pieces.size());
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const Mesh &m = pieces[p];
    merged[p].assign(m.num_vertices(), kNoVertex);
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
      const double id = gid >= 0 ? m.point_data[std::size_t(gid)].values[v] : -1.0;
      if (id >= 0) {
        if (by_id.emplace(id, 0).second)
          id_refs.push_back({p, VertexId(v)});
      } else {
        std::vector<double> key(m.point(VertexId(v)), m.point(VertexId(v)) + dim);
        if (by_point.emplace(std::move(key), 0).second)
          point_refs.push_back({p, VertexId(v)});
      }
    }
  }
  // Vertices with ids first, by id; then the others by coordinates (a
  // .pvtu from another tool: all of them), an order every rank count gives.
  Mesh out;
  out.dim = dim;
  out.physical_names = first.physical_names;
  for (const DataArray &a : first.point_data)
    if (a.name != kGlobalIdArray)
      out.point_data.push_back({a.name, a.components, {}, a.type});
  for (const DataArray &a : first.cell_data)
    out.cell_data.push_back({a.name, a.components, {}, a.type});
  std::vector<Ref> order;
  {
    VertexId next = 0;
    for (auto &[id, v] : by_id)
      v = next++;
    std::sort(id_refs.begin(), id_refs.end(), [&](const Ref &a, const Ref &b) {
      return pieces[a.piece].point_data[std::size_t(gid)].values[a.v] <
             pieces[b.piece].point_data[std::size_t(gid)].values[b.v];
    });
    for (auto &[key, v] : by_point)
      v = next++;
    std::sort(point_refs.begin(), point_refs.end(), [&](const Ref &a, const Ref &b) {
      const double *x = pieces[a.piece].point(a.v), *y = pieces[b.piece].point(b.v);
      return std::lexicographical_compare(x, x + dim, y, y + dim);
    });
    order = id_refs;
    order.insert(order.end(), point_refs.begin(), point_refs.end());
  }
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const Mesh &m = pieces[p];
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
      const double id = gid >= 0 ? m.point_data[std::size_t(gid)].values[v] : -1.0;
      merged[p][v] =
          id >= 0
              ? by_id.at(id)
              : by_point.at(std::vector<double>(m.point(VertexId(v)), m.point(VertexId(v)) + dim));
    }
  }
  for (const Ref &r : order) {
    const Mesh &m = pieces[r.piece];
    out.coords.insert(out.coords.end(), m.point(r.v), m.point(r.v) + dim);
    std::size_t k = 0;
    for (const DataArray &a : m.point_data) {
      if (a.name == kGlobalIdArray)
        continue;
      const std::size_t c = std::size_t(a.components);
      std::vector<double> &to = out.point_data[k++].values;
      to.insert(to.end(), a.values.begin() + std::ptrdiff_t(r.v * c),
                a.values.begin() + std::ptrdiff_t((r.v + 1) * c));
    }
  }
  // Cells piece after piece, with their arrays.
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const Mesh &m = pieces[p];
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      for (int i = 0; i < n; ++i)
        out.cells.push_back(merged[p][m.cell(CellId(c))[i]]);
    for (std::size_t a = 0; a < m.cell_data.size(); ++a)
      out.cell_data[a].values.insert(out.cell_data[a].values.end(), m.cell_data[a].values.begin(),
                                     m.cell_data[a].values.end());
  }
  // Lower-dimensional cells, a block per dimension (a piece without cells
  // of some dimension has no block for it): one on the border of two pieces
  // is in both; it is kept from the first piece that has it (as often as it
  // has it).
  std::vector<int> dims;
  for (const Mesh &m : pieces)
    for (const Entities &e : m.entities)
      dims.push_back(e.dim);
  std::sort(dims.begin(), dims.end());
  dims.erase(std::unique(dims.begin(), dims.end()), dims.end());
  for (const int dim_b : dims) {
    const Entities *model = nullptr;
    Entities block;
    block.dim = dim_b;
    std::map<std::array<VertexId, 4>, std::size_t> owner; // key -> first piece holding it
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      for (const Entities &e : pieces[p].entities) {
        if (e.dim != dim_b)
          continue;
        if (!model) {
          model = &e;
          for (const DataArray &a : e.data)
            block.data.push_back({a.name, a.components, {}, a.type});
        } else if (!same_arrays(e.data, model->data)) {
          throw InputError(path, "piece " + sources[p] + "'s cells of dimension " +
                                     std::to_string(dim_b) +
                                     " have other arrays than those of an earlier piece");
        }
        for (std::size_t i = 0; i < e.size(); ++i) {
          VertexId ids[4];
          for (int k = 0; k <= e.dim; ++k)
            ids[k] = merged[p][e.entity(i)[k]];
          const FaceKey key = face_key(ids, e.dim + 1);
          const std::size_t holder = owner.emplace(key.ids, p).first->second;
          if (holder != p)
            continue;
          block.vertices.insert(block.vertices.end(), ids, ids + e.dim + 1);
          for (std::size_t a = 0; a < e.data.size(); ++a) {
            const std::size_t c = std::size_t(e.data[a].components);
            block.data[a].values.insert(block.data[a].values.end(),
                                        e.data[a].values.begin() + std::ptrdiff_t(i * c),
                                        e.data[a].values.begin() + std::ptrdiff_t((i + 1) * c));
          }
        }
      }
    }
    out.entities.push_back(std::move(block));
  }
  tree_from_pieces(out, by_id.size(), path);
  return out;
}

} // namespace bisect
