// Distributed refinement (bisect/distributed.hpp): partition, exchange of
// bisected border edges, the final check across parts, gathering and .pvtu.
#include "bisect/distributed.hpp"
#include "bisect/coarsen.hpp"

// GCC 12 warns falsely about std::string concatenation (-Wrestrict, its bug
// 105329) and about std::sort's insertion step on a vector of structs
// (-Warray-bounds) in this file; neither is reachable.
#pragma GCC diagnostic ignored "-Wrestrict"
#pragma GCC diagnostic ignored "-Warray-bounds"

#include "bisect/error.hpp"
#include "bisect/output.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "core/arrays.hpp"
#include "core/faces.hpp"
#include "core/heights.hpp"
#include "core/reorder.hpp"
#include "engine/coarsen_pass.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace bisect {

Communicator::~Communicator() {
  if (c_ != MPI_COMM_NULL) {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized)
      MPI_Comm_free(&c_);
  }
}

Communicator &Communicator::operator=(Communicator &&o) noexcept {
  if (this != &o) {
    Communicator old(c_);
    c_ = o.c_;
    o.c_ = MPI_COMM_NULL;
  }
  return *this;
}

namespace {

// ---------------------------------------------------------------- buffers

// A flat byte buffer: what rank 0 sends each part, and what parts send back.
class Writer {
public:
  template <class T> void put(const T &v) {
    const auto *p = reinterpret_cast<const char *>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  template <class T> void put(const std::vector<T> &v) {
    put<std::uint64_t>(v.size());
    const auto *p = reinterpret_cast<const char *>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }
  void put(const std::string &s) {
    put<std::uint64_t>(s.size());
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  std::vector<char> bytes;
};

class Reader {
public:
  explicit Reader(const std::vector<char> &b) : b_(b) {}
  template <class T> T get() {
    T v;
    need(sizeof(T));
    std::memcpy(&v, b_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  template <class T> std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    need(n * sizeof(T));
    std::vector<T> v(n);
    if (n)
      std::memcpy(v.data(), b_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return v;
  }
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s(b_.data() + at_, n);
    at_ += n;
    return s;
  }

private:
  void need(std::size_t n) const {
    if (at_ + n > b_.size())
      throw CheckError("distributed: a message is shorter than its contents");
  }
  const std::vector<char> &b_;
  std::size_t at_ = 0;
};

void put_arrays(Writer &w, const std::vector<DataArray> &arrays,
                const std::vector<std::uint64_t> &ids) {
  w.put<std::uint64_t>(arrays.size());
  for (const DataArray &a : arrays) {
    w.put(a.name);
    w.put<std::int32_t>(a.components);
    w.put<std::uint8_t>(std::uint8_t(a.type));
    std::vector<double> v;
    v.reserve(ids.size() * std::size_t(a.components));
    for (std::uint64_t i : ids)
      for (int k = 0; k < a.components; ++k)
        v.push_back(a.values[i * std::size_t(a.components) + std::size_t(k)]);
    w.put(v);
  }
}

std::vector<DataArray> get_arrays(Reader &r) {
  std::vector<DataArray> arrays(r.get<std::uint64_t>());
  for (DataArray &a : arrays) {
    a.name = r.get_string();
    a.components = r.get<std::int32_t>();
    a.type = ValueType(r.get<std::uint8_t>());
    a.values = r.get_vector<double>();
  }
  return arrays;
}

// Sends and receives byte buffers larger than an int can count.
constexpr std::size_t kChunk = std::size_t(1) << 30;
void send_bytes(const std::vector<char> &b, int to, MPI_Comm comm) {
  std::uint64_t n = b.size();
  MPI_Send(&n, 1, MPI_UINT64_T, to, 1, comm);
  for (std::size_t at = 0; at < b.size(); at += kChunk)
    MPI_Send(b.data() + at, int(std::min(kChunk, b.size() - at)), MPI_CHAR, to, 2, comm);
}
std::vector<char> receive_bytes(int from, MPI_Comm comm) {
  std::uint64_t n = 0;
  MPI_Recv(&n, 1, MPI_UINT64_T, from, 1, comm, MPI_STATUS_IGNORE);
  std::vector<char> b(n);
  for (std::size_t at = 0; at < b.size(); at += kChunk)
    MPI_Recv(b.data() + at, int(std::min(kChunk, b.size() - at)), MPI_CHAR, from, 2, comm,
             MPI_STATUS_IGNORE);
  return b;
}

// ---------------------------------------------------------------- points

// Vertices by their coordinates: an open-addressing table of vertex ids.
class PointIndex {
public:
  PointIndex(const std::vector<double> &coords, int dim) : coords_(coords), dim_(dim) {}
  // The vertex at p, or kNoVertex.
  VertexId find(const double *p) const {
    if (slots_.empty())
      return kNoVertex;
    for (std::size_t i = slot(p);; i = (i + 1) & mask_) {
      const VertexId v = slots_[i];
      if (v == kNoVertex)
        return kNoVertex;
      if (std::equal(p, p + dim_, coords_.data() + std::size_t(v) * dim_))
        return v;
    }
  }
  // Adds vertex v (its coordinates in `coords`); returns the vertex already
  // there with the same coordinates, or v.
  VertexId add(VertexId v) {
    if ((size_ + 1) * 2 > slots_.size())
      grow();
    const double *p = coords_.data() + std::size_t(v) * dim_;
    for (std::size_t i = slot(p);; i = (i + 1) & mask_) {
      const VertexId w = slots_[i];
      if (w == kNoVertex) {
        slots_[i] = v;
        ++size_;
        return v;
      }
      if (std::equal(p, p + dim_, coords_.data() + std::size_t(w) * dim_))
        return w;
    }
  }

private:
  std::size_t slot(const double *p) const {
    std::uint64_t h = 0x243F6A8885A308D3ull;
    for (int k = 0; k < dim_; ++k) {
      double x = p[k] == 0 ? 0.0 : p[k]; // -0 and +0 are one point
      std::uint64_t b;
      std::memcpy(&b, &x, 8);
      h = (h ^ b) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 29;
    }
    return std::size_t(h) & mask_;
  }
  void grow() {
    std::vector<VertexId> old = std::move(slots_);
    slots_.assign(std::max<std::size_t>(1024, old.size() * 2), kNoVertex);
    mask_ = slots_.size() - 1;
    size_ = 0;
    for (VertexId v : old)
      if (v != kNoVertex)
        add(v);
  }
  const std::vector<double> &coords_;
  int dim_;
  std::vector<VertexId> slots_;
  std::size_t size_ = 0, mask_ = 0;
};

// ---------------------------------------------------------------- Hilbert

// The position along a Hilbert curve of the point with integer coordinates
// x[0..n) of `bits` bits each (n * bits <= 64): J. Skilling's transpose
// method ("Programming the Hilbert curve", AIP Conf. Proc. 707, 2004).
std::uint64_t hilbert_index(std::uint32_t *x, int n, int bits) {
  const std::uint32_t top = std::uint32_t(1) << (bits - 1);
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    const std::uint32_t p = q - 1;
    for (int i = 0; i < n; ++i)
      if (x[i] & q) {
        x[0] ^= p;
      } else {
        const std::uint32_t t = (x[0] ^ x[i]) & p;
        x[0] ^= t;
        x[i] ^= t;
      }
  }
  for (int i = 1; i < n; ++i)
    x[i] ^= x[i - 1];
  std::uint32_t t = 0;
  for (std::uint32_t q = top; q > 1; q >>= 1)
    if (x[n - 1] & q)
      t ^= q - 1;
  for (int i = 0; i < n; ++i)
    x[i] ^= t;
  std::uint64_t h = 0;
  for (int b = bits - 1; b >= 0; --b)
    for (int i = 0; i < n; ++i)
      h = h << 1 | ((x[i] >> b) & 1);
  return h;
}

// part[c] for every cell: equal stretches of the cells in Hilbert order of
// their centroids (ties by cell id).
std::vector<int> hilbert_parts(const Mesh &m, int parts) {
  const int d = m.dim, bits = std::min(21, 64 / d);
  const std::size_t nc = m.num_cells();
  std::vector<double> lo(d, std::numeric_limits<double>::infinity()), hi(d, -lo[0]);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    for (int k = 0; k < d; ++k) {
      lo[k] = std::min(lo[k], m.point(VertexId(v))[k]);
      hi[k] = std::max(hi[k], m.point(VertexId(v))[k]);
    }
  const double scale = double((std::uint64_t(1) << bits) - 1);
  std::vector<std::pair<std::uint64_t, CellId>> keys(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    std::uint32_t x[4];
    for (int k = 0; k < d; ++k) {
      double s = 0;
      for (int i = 0; i <= d; ++i)
        s += m.point(m.cell(CellId(c))[i])[k];
      const double ext = hi[k] - lo[k];
      const double u = ext > 0 ? (s / (d + 1) - lo[k]) / ext : 0.0;
      x[k] = std::uint32_t(std::clamp(u, 0.0, 1.0) * scale);
    }
    keys[c] = {hilbert_index(x, d, bits), CellId(c)};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> part(nc);
  for (std::size_t i = 0; i < nc; ++i)
    part[keys[i].second] = int(i * std::size_t(parts) / nc);
  return part;
}

// ---------------------------------------------------------------- helpers

// A mesh with no part yet, on a duplicate of `comm`.
DistributedMesh on_communicator(MPI_Comm comm) {
  DistributedMesh d;
  MPI_Comm dup;
  MPI_Comm_dup(comm, &dup);
  d.comm = Communicator(dup);
  MPI_Comm_rank(dup, &d.rank);
  MPI_Comm_size(dup, &d.size);
  return d;
}

// The rank at which a point's coordinates are known (a hash of its bits).
int home_rank(const double *p, int dim, int size) {
  std::uint64_t h = 0x243F6A8885A308D3ull;
  for (int k = 0; k < dim; ++k) {
    double x = p[k] == 0 ? 0.0 : p[k];
    std::uint64_t b;
    std::memcpy(&b, &x, 8);
    h = (h ^ b) * 0x9E3779B97F4A7C15ull;
    h ^= h >> 29;
  }
  return int(h % static_cast<std::uint64_t>(size));
}

// send[r] to rank r, for every r, as MPI type `type`; returns what each rank
// sent here. Collective.
template <class T>
std::vector<std::vector<T>> all_to_all(const std::vector<std::vector<T>> &send, MPI_Comm comm,
                                       MPI_Datatype type = MPI_DOUBLE) {
  const std::size_t np = send.size();
  std::vector<int> sc(np), rc(np), sd(np + 1, 0), rd(np + 1, 0);
  for (std::size_t r = 0; r < np; ++r)
    sc[r] = int(send[r].size());
  MPI_Alltoall(sc.data(), 1, MPI_INT, rc.data(), 1, MPI_INT, comm);
  std::vector<T> flat;
  for (std::size_t r = 0; r < np; ++r) {
    sd[r + 1] = sd[r] + sc[r];
    rd[r + 1] = rd[r] + rc[r];
    flat.insert(flat.end(), send[r].begin(), send[r].end());
  }
  std::vector<T> got(std::size_t(std::max(rd[np], 1)));
  MPI_Alltoallv(flat.data(), sc.data(), sd.data(), type, got.data(), rc.data(), rd.data(), type,
                comm);
  std::vector<std::vector<T>> out(np);
  for (std::size_t r = 0; r < np; ++r)
    out[r].assign(got.begin() + rd[r], got.begin() + rd[r + 1]);
  return out;
}

std::vector<int> intersect(const std::vector<int> &a, const std::vector<int> &b) {
  std::vector<int> out;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

// Exchanges variable-length double buffers with the graph neighbours:
// out[i] goes to d.neighbours[i]; returns what each neighbour sent.
std::vector<std::vector<double>> trade(const DistributedMesh &d,
                                       const std::vector<std::vector<double>> &out) {
  const std::size_t n = d.neighbours.size();
  std::vector<int> send_counts(n), recv_counts(n), send_displs(n), recv_displs(n);
  std::vector<double> send;
  for (std::size_t i = 0; i < n; ++i) {
    send_displs[i] = int(send.size());
    send_counts[i] = int(out[i].size());
    send.insert(send.end(), out[i].begin(), out[i].end());
  }
  MPI_Neighbor_alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT,
                        d.graph.get());
  int total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    recv_displs[i] = total;
    total += recv_counts[i];
  }
  std::vector<double> recv(std::size_t(std::max(total, 1)));
  MPI_Neighbor_alltoallv(send.empty() ? nullptr : send.data(), send_counts.data(),
                         send_displs.data(), MPI_DOUBLE, recv.data(), recv_counts.data(),
                         recv_displs.data(), MPI_DOUBLE, d.graph.get());
  std::vector<std::vector<double>> in(n);
  for (std::size_t i = 0; i < n; ++i)
    in[i].assign(recv.begin() + recv_displs[i], recv.begin() + recv_displs[i] + recv_counts[i]);
  return in;
}

// The measure of the facet with vertices f[0..dim) of a dim-D mesh: the
// square root of its Gram determinant over (dim-1)!.
double facet_measure(const Mesh &m, const VertexId *f) {
  const int k = m.dim - 1;
  double e[3][4], gram[9];
  for (int i = 0; i < k; ++i)
    for (int c = 0; c < m.dim; ++c)
      e[i][c] = m.point(f[i + 1])[c] - m.point(f[0])[c];
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      double s = 0;
      for (int c = 0; c < m.dim; ++c)
        s += e[i][c] * e[j][c];
      gram[i * k + j] = s;
    }
  const double factorial = k == 3 ? 6.0 : k == 2 ? 2.0 : 1.0;
  return std::sqrt(std::max(0.0, determinant(gram, k))) / factorial;
}

// Root's string, on every rank.
std::string broadcast(std::string text, int root, MPI_Comm comm) {
  std::uint64_t len = text.size();
  MPI_Bcast(&len, 1, MPI_UINT64_T, root, comm);
  text.resize(len);
  MPI_Bcast(text.data(), int(len), MPI_CHAR, root, comm);
  return text;
}

// The lowest rank whose `failure` is not empty (size when none), with its
// message, on every rank.
struct Failure {
  int rank;
  std::string message;
};
Failure first_failure(const std::string &failure, int rank, int size, MPI_Comm comm) {
  int failing = failure.empty() ? size : rank, first = size;
  MPI_Allreduce(&failing, &first, 1, MPI_INT, MPI_MIN, comm);
  return {first, first < size ? broadcast(failure, first, comm) : std::string()};
}

// slot[r]: the index of rank r in d.neighbours (unused for the others).
std::vector<std::size_t> neighbour_slots(const DistributedMesh &d) {
  std::vector<std::size_t> slot(std::size_t(d.size), std::size_t(-1));
  for (std::size_t i = 0; i < d.neighbours.size(); ++i)
    slot[std::size_t(d.neighbours[i])] = i;
  return slot;
}

bool any_rank(bool mine, MPI_Comm comm) {
  int v = mine, all = 0;
  MPI_Allreduce(&v, &all, 1, MPI_INT, MPI_LOR, comm);
  return all != 0;
}

std::size_t sum_ranks(std::size_t mine, MPI_Comm comm) {
  std::uint64_t v = mine, all = 0;
  MPI_Allreduce(&v, &all, 1, MPI_UINT64_T, MPI_SUM, comm);
  return std::size_t(all);
}

} // namespace

// ---------------------------------------------------------------- distribute

DistributedMesh distribute(const Mesh &mesh, int root, MPI_Comm comm) {
  DistributedMesh d = on_communicator(comm);
  MPI_Comm dup = d.comm.get();

  // Rank 0 says whether the mesh can be split before anyone waits for a part.
  std::string refusal;
  if (d.rank == root) {
    if (!mesh.marked())
      refusal = "the mesh is not marked";
    else if (mesh.num_cells() < std::size_t(d.size))
      refusal = "the mesh has " + std::to_string(mesh.num_cells()) + " cells, fewer than the " +
                std::to_string(d.size) + " ranks";
  }
  refusal = broadcast(refusal, root, dup);
  if (!refusal.empty())
    throw UsageError("distributed refinement: " + refusal);

  std::vector<char> mine;
  if (d.rank == root) {
    const int n = mesh.cell_size();
    const std::vector<int> part = hilbert_parts(mesh, d.size);
    std::vector<std::vector<std::uint64_t>> cells_of(std::size_t(d.size));
    for (std::size_t c = 0; c < part.size(); ++c)
      cells_of[std::size_t(part[c])].push_back(c);
    // holders[v]: the parts whose cells hold v, increasing (CSR).
    const std::size_t nv = mesh.num_vertices();
    // visit(v, p) once for every part p holding v, parts in increasing order.
    std::vector<std::uint32_t> last(nv);
    auto for_each_holder = [&](auto &&visit) {
      std::fill(last.begin(), last.end(), std::uint32_t(-1));
      for (int p = 0; p < d.size; ++p)
        for (std::uint64_t c : cells_of[std::size_t(p)])
          for (int i = 0; i < n; ++i) {
            const VertexId v = mesh.cell(CellId(c))[i];
            if (last[v] != std::uint32_t(p)) {
              last[v] = std::uint32_t(p);
              visit(v, p);
            }
          }
    };
    std::vector<std::uint32_t> count(nv + 1, 0);
    for_each_holder([&](VertexId v, int) { ++count[v + 1]; });
    std::partial_sum(count.begin(), count.end(), count.begin());
    std::vector<std::int32_t> holders(count[nv]);
    std::vector<std::uint32_t> fill(count.begin(), count.end() - 1);
    for_each_holder([&](VertexId v, int p) { holders[fill[v]++] = p; });
    std::vector<VertexId> local_id(nv, kNoVertex);
    // Tagged entities: each goes to every part with a cell it is a face of.
    std::vector<std::unordered_multimap<FaceKey, std::uint64_t, FaceKeyHash>> entity_index(
        mesh.entities.size());
    for (std::size_t b = 0; b < mesh.entities.size(); ++b)
      for (std::size_t i = 0; i < mesh.entities[b].size(); ++i)
        entity_index[b].emplace(face_key(mesh.entities[b].entity(i), mesh.entities[b].dim + 1), i);
    for (int p = 0; p < d.size; ++p) {
      const std::vector<std::uint64_t> &cells = cells_of[std::size_t(p)];
      std::vector<std::uint64_t> verts;
      for (std::uint64_t c : cells)
        for (int i = 0; i < n; ++i)
          verts.push_back(mesh.cell(CellId(c))[i]);
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      for (std::size_t i = 0; i < verts.size(); ++i)
        local_id[verts[i]] = VertexId(i);
      Writer w;
      w.put<std::int32_t>(mesh.dim);
      w.put<std::uint8_t>(std::uint8_t(mesh.marking));
      w.put(verts);
      std::vector<double> coords;
      coords.reserve(verts.size() * std::size_t(mesh.dim));
      for (std::uint64_t v : verts)
        coords.insert(coords.end(), mesh.point(VertexId(v)), mesh.point(VertexId(v)) + mesh.dim);
      w.put(coords);
      std::vector<VertexId> conn;
      std::vector<std::uint8_t> stage, tag;
      conn.reserve(cells.size() * std::size_t(n));
      for (std::uint64_t c : cells) {
        for (int i = 0; i < n; ++i)
          conn.push_back(local_id[mesh.cell(CellId(c))[i]]);
        stage.push_back(std::uint8_t(mesh.stage[c]));
        tag.push_back(mesh.tag[c]);
      }
      w.put(conn);
      w.put(stage);
      w.put(tag);
      put_arrays(w, mesh.point_data, verts);
      put_arrays(w, mesh.cell_data, cells);
      // The other parts holding each vertex.
      std::vector<std::uint32_t> offsets{0};
      std::vector<std::int32_t> others;
      for (std::uint64_t v : verts) {
        for (std::uint32_t k = count[v]; k < count[v + 1]; ++k)
          if (holders[k] != p)
            others.push_back(holders[k]);
        offsets.push_back(std::uint32_t(others.size()));
      }
      w.put(offsets);
      w.put(others);
      // Explicit marking: the ranks of the part's edges, in its ids.
      std::vector<std::uint64_t> rank_keys;
      std::vector<std::uint32_t> rank_values;
      for (const auto &[key, r] : mesh.edge_rank) {
        const VertexId a = VertexId(key >> 32), b = VertexId(key & 0xffffffffu);
        if (a < nv && b < nv && local_id[a] != kNoVertex && local_id[b] != kNoVertex) {
          rank_keys.push_back(edge_key(local_id[a], local_id[b]));
          rank_values.push_back(r);
        }
      }
      w.put(rank_keys);
      w.put(rank_values);
      w.put<std::uint64_t>(mesh.physical_names.size());
      for (const PhysicalName &pn : mesh.physical_names) {
        w.put<std::int32_t>(pn.dim);
        w.put<std::int32_t>(pn.tag);
        w.put(pn.name);
      }
      // The tree, where the part holds a vertex's parents.
      w.put<std::uint8_t>(mesh.has_tree());
      if (mesh.has_tree()) {
        std::vector<std::uint16_t> generation, level;
        std::vector<VertexId> parents;
        for (std::uint64_t c : cells)
          generation.push_back(mesh.generation[c]);
        for (std::uint64_t v : verts) {
          const VertexId a = mesh.parent_edge[2 * v], b = mesh.parent_edge[2 * v + 1];
          const bool here = a != kNoVertex && local_id[a] != kNoVertex && local_id[b] != kNoVertex;
          parents.push_back(here ? local_id[a] : kNoVertex);
          parents.push_back(here ? local_id[b] : kNoVertex);
          level.push_back(mesh.level.size() == nv ? mesh.level[v] : std::uint16_t(a != kNoVertex));
        }
        w.put(generation);
        w.put(parents);
        w.put(level);
        // Every vertex's parents by their coordinates (NaN: an original
        // vertex), for the tree of a .pvtu's pieces (write_pvtu).
        std::vector<double> parent_points(verts.size() * 2 * std::size_t(mesh.dim),
                                          std::numeric_limits<double>::quiet_NaN());
        for (std::size_t i = 0; i < verts.size(); ++i) {
          const VertexId a = mesh.parent_edge[2 * verts[i]], b = mesh.parent_edge[2 * verts[i] + 1];
          if (a == kNoVertex)
            continue;
          double *to = parent_points.data() + i * 2 * std::size_t(mesh.dim);
          std::copy_n(mesh.point(a), mesh.dim, to);
          std::copy_n(mesh.point(b), mesh.dim, to + mesh.dim);
        }
        w.put(parent_points);
      }
      w.put<std::uint64_t>(mesh.entities.size());
      for (std::size_t b = 0; b < mesh.entities.size(); ++b) {
        const Entities &block = mesh.entities[b];
        std::vector<std::uint64_t> taken;
        for (std::uint64_t c : cells)
          for_each_face(mesh.cell(CellId(c)), n, block.dim, [&](const VertexId *f, int count) {
            auto [lo, hi] = entity_index[b].equal_range(face_key(f, count));
            for (auto it = lo; it != hi; ++it)
              taken.push_back(it->second);
          });
        std::sort(taken.begin(), taken.end());
        taken.erase(std::unique(taken.begin(), taken.end()), taken.end());
        std::vector<VertexId> ids;
        for (std::uint64_t i : taken)
          for (int k = 0; k <= block.dim; ++k)
            ids.push_back(local_id[block.entity(i)[k]]);
        w.put<std::int32_t>(block.dim);
        w.put(ids);
        put_arrays(w, block.data, taken);
      }
      for (std::uint64_t v : verts)
        local_id[v] = kNoVertex;
      if (p == root)
        mine = std::move(w.bytes);
      else
        send_bytes(w.bytes, p, dup);
    }
  } else {
    mine = receive_bytes(root, dup);
  }

  Reader r(mine);
  Mesh &m = d.local;
  m.dim = r.get<std::int32_t>();
  m.marking = Marking(r.get<std::uint8_t>());
  d.input_vertex = r.get_vector<std::uint64_t>();
  m.coords = r.get_vector<double>();
  m.cells = r.get_vector<VertexId>();
  for (std::uint8_t s : r.get_vector<std::uint8_t>())
    m.stage.push_back(Stage(s));
  m.tag = r.get_vector<std::uint8_t>();
  m.point_data = get_arrays(r);
  m.cell_data = get_arrays(r);
  const std::vector<std::uint32_t> offsets = r.get_vector<std::uint32_t>();
  const std::vector<std::int32_t> others = r.get_vector<std::int32_t>();
  d.sharers.resize(d.input_vertex.size());
  for (std::size_t v = 0; v < d.sharers.size(); ++v)
    d.sharers[v].assign(others.begin() + offsets[v], others.begin() + offsets[v + 1]);
  const std::vector<std::uint64_t> rank_keys = r.get_vector<std::uint64_t>();
  const std::vector<std::uint32_t> rank_values = r.get_vector<std::uint32_t>();
  for (std::size_t i = 0; i < rank_keys.size(); ++i)
    m.edge_rank[rank_keys[i]] = rank_values[i];
  m.physical_names.resize(r.get<std::uint64_t>());
  for (PhysicalName &pn : m.physical_names) {
    pn.dim = r.get<std::int32_t>();
    pn.tag = r.get<std::int32_t>();
    pn.name = r.get_string();
  }
  if (r.get<std::uint8_t>()) {
    m.generation = r.get_vector<std::uint16_t>();
    m.parent_edge = r.get_vector<VertexId>();
    m.level = r.get_vector<std::uint16_t>();
    d.parent_points = r.get_vector<double>();
  }
  m.entities.resize(r.get<std::uint64_t>());
  for (Entities &block : m.entities) {
    block.dim = r.get<std::int32_t>();
    block.vertices = r.get_vector<VertexId>();
    block.data = get_arrays(r);
  }
  if (d.rank == root && mesh.has_tree()) {
    d.input_parent_edge = mesh.parent_edge;
    d.input_level = mesh.level.size() == mesh.num_vertices()
                        ? mesh.level
                        : std::vector<std::uint16_t>(mesh.num_vertices(), 0);
    if (mesh.level.size() != mesh.num_vertices())
      for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
        d.input_level[v] = mesh.parent_edge[2 * v] != kNoVertex;
  }

  std::vector<int> nb(others.begin(), others.end());
  std::sort(nb.begin(), nb.end());
  nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  d.neighbours = nb;
  MPI_Comm graph;
  MPI_Dist_graph_create_adjacent(dup, int(nb.size()), nb.empty() ? MPI_WEIGHTS_EMPTY : nb.data(),
                                 MPI_UNWEIGHTED, int(nb.size()),
                                 nb.empty() ? MPI_WEIGHTS_EMPTY : nb.data(), MPI_UNWEIGHTED,
                                 MPI_INFO_NULL, 0, &graph);
  d.graph = Communicator(graph);
  count_global(d);
  return d;
}

// ---------------------------------------------------------------- refine

DistributedRefineResult refine(DistributedMesh &d, const std::vector<CellId> &selected,
                               const RefineLimits &limits) {
  using clock = std::chrono::steady_clock;
  DistributedRefineResult result;
  Mesh &m = d.local;
  const int dim = m.dim;
  // Only vertices another rank may hold are looked up (the ends of a
  // received edge, and its midpoint if made here: see distributed.hpp).
  PointIndex index(m.coords, dim);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (!d.sharers[v].empty())
      index.add(VertexId(v));
  std::size_t bisections = 0;
  bool precision = false;
  // The iteration's vertices all get one level (each refine() call below
  // would count itself one), the same on every rank.
  int newest = m.level.empty() ? 0 : *std::max_element(m.level.begin(), m.level.end());
  int level = 0;
  MPI_Allreduce(&newest, &level, 1, MPI_INT, MPI_MAX, d.comm.get());
  level = std::min(level + 1, int(std::numeric_limits<std::uint16_t>::max()));
  const std::size_t first_new = m.num_vertices();
  std::size_t made_from = m.num_vertices();
  // A local refine that throws (an internal check) must not leave the other
  // ranks waiting: its message goes to every rank at the next agreement.
  std::string failure;
  auto local_refine = [&](const std::vector<CellId> &cells,
                          const std::vector<std::array<VertexId, 2>> &split) {
    try {
      const RefineResult r = refine(m, cells, split, limits);
      bisections += r.bisections;
      precision |= r.limit_reached;
    } catch (const std::exception &e) {
      failure = e.what();
    }
  };
  local_refine(selected, {});
  const std::vector<std::size_t> slot_of = neighbour_slots(d);
  std::vector<double> pending; // received edges with an end not here (yet)
  for (;;) {
    // The vertices made since the last exchange: who may hold them, and the
    // edges they split, for those ranks.
    std::vector<std::vector<double>> out(d.neighbours.size());
    d.sharers.resize(m.num_vertices());
    for (std::size_t v = made_from; failure.empty() && v < m.num_vertices(); ++v) {
      const VertexId a = m.parent_edge[2 * v], b = m.parent_edge[2 * v + 1];
      d.sharers[v] = intersect(d.sharers[a], d.sharers[b]);
      if (!d.sharers[v].empty())
        index.add(VertexId(v));
      for (int rank : d.sharers[v]) {
        std::vector<double> &o = out[slot_of[std::size_t(rank)]];
        o.insert(o.end(), m.point(a), m.point(a) + dim);
        o.insert(o.end(), m.point(b), m.point(b) + dim);
        ++result.edges_sent;
      }
    }
    made_from = m.num_vertices();
    const auto t0 = clock::now();
    const std::vector<std::vector<double>> in = trade(d, out);
    // The edges this part holds and has not bisected yet. An edge whose end
    // is not here yet may be one a neighbour bisected after making that end
    // in the same round (this part makes the end from another edge of the
    // same message): it waits, and is looked at again after every round.
    std::vector<std::array<VertexId, 2>> split;
    std::vector<double> waiting;
    auto consider = [&](const double *edge) {
      const VertexId a = index.find(edge), b = index.find(edge + dim);
      if (a == kNoVertex || b == kNoVertex) {
        waiting.insert(waiting.end(), edge, edge + 2 * dim);
        return;
      }
      double mid[4];
      for (int k = 0; k < dim; ++k)
        mid[k] = 0.5 * (m.point(a)[k] + m.point(b)[k]);
      if (index.find(mid) == kNoVertex)
        split.push_back({a, b});
    };
    for (std::size_t at = 0; at + 2 * std::size_t(dim) <= pending.size(); at += 2 * dim)
      consider(pending.data() + at);
    for (const std::vector<double> &edges : in)
      for (std::size_t at = 0; at + 2 * std::size_t(dim) <= edges.size(); at += 2 * dim)
        consider(edges.data() + at);
    pending = std::move(waiting);
    std::sort(split.begin(), split.end());
    split.erase(std::unique(split.begin(), split.end()), split.end());
    const bool stop = precision || !failure.empty();
    const bool more = any_rank(!split.empty() || stop, d.comm.get());
    result.exchange_seconds += std::chrono::duration<double>(clock::now() - t0).count();
    if (!more || any_rank(stop, d.comm.get()))
      break;
    ++result.rounds;
    local_refine({}, split);
  }
  if (const Failure f = first_failure(failure, d.rank, d.size, d.comm.get()); f.rank < d.size)
    throw CheckError("part " + std::to_string(f.rank) + ": " + f.message);
  result.precision_reached = any_rank(precision, d.comm.get());
  result.selected = sum_ranks(selected.size(), d.comm.get());
  result.bisections = sum_ranks(bisections, d.comm.get());
  for (std::size_t v = first_new; v < m.level.size(); ++v)
    m.level[v] = std::uint16_t(level);
  count_global(d);
  return result;
}

void count_global(DistributedMesh &d) {
  // A vertex is counted by the lowest rank holding it (sharers are a
  // superset, so a vertex some lower rank only might hold is confirmed by
  // asking: here, by its coordinates).
  const Mesh &m = d.local;
  d.global_cells = sum_ranks(m.num_cells(), d.comm.get());
  std::vector<std::vector<double>> out(d.neighbours.size());
  const std::vector<std::size_t> slot_of = neighbour_slots(d);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    for (int r : d.sharers[v])
      if (r > d.rank) {
        std::vector<double> &o = out[slot_of[std::size_t(r)]];
        o.insert(o.end(), m.point(VertexId(v)), m.point(VertexId(v)) + m.dim);
      }
  const std::vector<std::vector<double>> in = trade(d, out);
  PointIndex index(m.coords, m.dim);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (!d.sharers[v].empty())
      index.add(VertexId(v));
  std::vector<std::uint8_t> counted_elsewhere(m.num_vertices(), 0);
  for (std::size_t i = 0; i < in.size(); ++i)
    if (d.neighbours[i] < d.rank)
      for (std::size_t at = 0; at + std::size_t(m.dim) <= in[i].size(); at += std::size_t(m.dim)) {
        const VertexId v = index.find(in[i].data() + at);
        if (v != kNoVertex)
          counted_elsewhere[v] = 1;
      }
  std::size_t mine = 0;
  for (std::uint8_t c : counted_elsewhere)
    mine += !c;
  d.global_vertices = sum_ranks(mine, d.comm.get());
}

QualitySummary quality_summary(const DistributedMesh &d) {
  const QualitySummary q = quality_summary(d.local);
  double mins[2] = {q.min, -q.max}, all[2];
  MPI_Allreduce(mins, all, 2, MPI_DOUBLE, MPI_MIN, d.comm.get());
  const double sum = q.mean * double(d.local.num_cells());
  double total = 0;
  MPI_Allreduce(&sum, &total, 1, MPI_DOUBLE, MPI_SUM, d.comm.get());
  return {all[0], -all[1], d.global_cells ? total / double(d.global_cells) : 0.0};
}

// ---------------------------------------------------------------- check

namespace {

// The facets on this part's border with other parts, as matched now: each
// facet of one cell here whose vertices all have some rank in common is
// sent, by its sorted vertex coordinates, to those ranks; the measure of
// those another part has too is summed. `twice` is set when a facet is
// matched by two parts (a facet in three cells).
double matched_border_measure(const DistributedMesh &d, bool &twice) {
  const Mesh &m = d.local;
  const int dim = m.dim, n = m.cell_size();
  const std::vector<std::size_t> slot_of = neighbour_slots(d);
  // Facets of the cells with dim shared vertices or more, counted.
  std::unordered_map<FaceKey, int, FaceKeyHash> count;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const VertexId *x = m.cell(CellId(c));
    int shared = 0;
    for (int i = 0; i < n; ++i)
      shared += !d.sharers[x[i]].empty();
    if (shared < dim)
      continue;
    for_each_face(x, n, dim - 1, [&](const VertexId *f, int k) {
      for (int i = 0; i < k; ++i)
        if (d.sharers[f[i]].empty())
          return;
      ++count[face_key(f, k)];
    });
  }
  std::map<std::vector<double>, std::pair<double, int>> alone; // key -> measure, matches
  std::vector<std::vector<double>> out(d.neighbours.size());
  for (const auto &[face, k] : count) {
    if (k != 1)
      continue;
    std::vector<int> ranks = d.sharers[face.ids[0]];
    for (int i = 1; i < dim && !ranks.empty(); ++i)
      ranks = intersect(ranks, d.sharers[face.ids[std::size_t(i)]]);
    if (ranks.empty())
      continue;
    std::vector<std::vector<double>> pts;
    for (int i = 0; i < dim; ++i)
      pts.emplace_back(m.point(face.ids[std::size_t(i)]), m.point(face.ids[std::size_t(i)]) + dim);
    std::sort(pts.begin(), pts.end());
    std::vector<double> key;
    for (const std::vector<double> &p : pts)
      key.insert(key.end(), p.begin(), p.end());
    alone[key] = {facet_measure(m, face.ids.data()), 0};
    for (int r : ranks) {
      std::vector<double> &o = out[slot_of[std::size_t(r)]];
      o.insert(o.end(), key.begin(), key.end());
    }
  }
  const std::vector<std::vector<double>> in = trade(d, out);
  const std::size_t width = std::size_t(dim) * std::size_t(dim);
  for (const std::vector<double> &keys : in)
    for (std::size_t at = 0; at + width <= keys.size(); at += width) {
      auto it = alone.find(std::vector<double>(keys.begin() + at, keys.begin() + at + width));
      if (it != alone.end())
        ++it->second.second;
    }
  double matched = 0;
  twice = false;
  for (const auto &[key, mc] : alone) {
    if (mc.second >= 1)
      matched += mc.first;
    twice |= mc.second > 1;
  }
  return matched;
}

} // namespace

double border_measure(const DistributedMesh &d) {
  bool twice = false;
  return matched_border_measure(d, twice);
}

CheckResult check_refined(const DistributedMesh &d, const Invariants &part_original,
                          double border_original) {
  const CheckResult local = check_refined(d.local, part_original);
  bool twice = false;
  const double matched = matched_border_measure(d, twice);
  // Each part's border is covered by facets the part beyond has too: a
  // facet split on one side only leaves halves that match nothing.
  const bool short_border =
      std::abs(matched - border_original) > 1e-9 * std::max(1.0, std::abs(border_original));
  int flags[3] = {!local.ok, twice, short_border}, any[3];
  MPI_Allreduce(flags, any, 3, MPI_INT, MPI_LOR, d.comm.get());
  CheckResult result;
  auto fail = [&](const std::string &why) {
    result.ok = false;
    result.failure = why;
  };
  if (any[0]) {
    const std::string mine = local.ok                ? std::string()
                             : local.failure.empty() ? "its final check"
                                                     : local.failure;
    const Failure f = first_failure(mine, d.rank, d.size, d.comm.get());
    fail("part " + std::to_string(f.rank) + ": " + f.message);
  } else if (any[1]) {
    fail("a facet is shared by three or more cells across parts");
  } else if (any[2]) {
    int failing = short_border ? d.rank : d.size, first = 0;
    MPI_Allreduce(&failing, &first, 1, MPI_INT, MPI_MIN, d.comm.get());
    fail("part " + std::to_string(first) +
         ": its border with other parts is not matched facet by facet (a facet on a border "
         "is split on one side only)");
  }
  return result;
}

// ---------------------------------------------------------------- gather

Mesh gather(const DistributedMesh &d, int root) {
  const Mesh &m = d.local;
  Writer w;
  w.put(d.input_vertex);
  w.put(m.coords);
  w.put(m.cells);
  std::vector<std::uint8_t> stage(m.stage.size());
  for (std::size_t c = 0; c < stage.size(); ++c)
    stage[c] = std::uint8_t(m.stage[c]);
  w.put(stage);
  w.put(m.tag);
  std::vector<std::uint64_t> all_v(m.num_vertices()), all_c(m.num_cells());
  std::iota(all_v.begin(), all_v.end(), 0);
  std::iota(all_c.begin(), all_c.end(), 0);
  put_arrays(w, m.point_data, all_v);
  put_arrays(w, m.cell_data, all_c);
  w.put<std::uint64_t>(m.entities.size());
  for (const Entities &block : m.entities) {
    w.put<std::int32_t>(block.dim);
    w.put(block.vertices);
    std::vector<std::uint64_t> all_e(block.size());
    std::iota(all_e.begin(), all_e.end(), 0);
    put_arrays(w, block.data, all_e);
  }
  w.put<std::uint8_t>(m.has_tree());
  if (m.has_tree()) {
    w.put(m.generation);
    w.put(m.parent_edge);
    w.put(m.level);
    w.put(d.parent_points);
  }
  if (d.rank != root) {
    send_bytes(w.bytes, root, d.comm.get());
    return Mesh{};
  }
  const int n = m.cell_size(), dim = m.dim;
  Mesh g;
  g.dim = dim;
  g.marking = m.marking;
  g.physical_names = m.physical_names;
  // Parts' vertices merged by coordinates into g; per part, its ids in g.
  struct Part {
    std::vector<std::uint64_t> input_vertex;
    std::vector<double> coords;
    std::vector<VertexId> cells;
    std::vector<std::uint8_t> stage, tag;
    std::vector<DataArray> point_data, cell_data;
    std::vector<Entities> entities;
    std::vector<std::uint16_t> generation, level;
    std::vector<VertexId> parent_edge;
    std::vector<double> parent_points;
  };
  std::vector<Part> parts(std::size_t(d.size));
  for (int p = 0; p < d.size; ++p) {
    const std::vector<char> bytes = p == root ? w.bytes : receive_bytes(p, d.comm.get());
    Reader r(bytes);
    Part &part = parts[std::size_t(p)];
    part.input_vertex = r.get_vector<std::uint64_t>();
    part.coords = r.get_vector<double>();
    part.cells = r.get_vector<VertexId>();
    part.stage = r.get_vector<std::uint8_t>();
    part.tag = r.get_vector<std::uint8_t>();
    part.point_data = get_arrays(r);
    part.cell_data = get_arrays(r);
    part.entities.resize(r.get<std::uint64_t>());
    for (Entities &block : part.entities) {
      block.dim = r.get<std::int32_t>();
      block.vertices = r.get_vector<VertexId>();
      block.data = get_arrays(r);
    }
    if (r.get<std::uint8_t>()) {
      part.generation = r.get_vector<std::uint16_t>();
      part.parent_edge = r.get_vector<VertexId>();
      part.level = r.get_vector<std::uint16_t>();
      part.parent_points = r.get_vector<double>();
    }
  }
  // Input vertices first, at their input ids (every input vertex is in some
  // part: prepare_input refuses unused vertices... or they were dropped).
  std::uint64_t inputs = 0;
  for (const Part &p : parts)
    for (std::uint64_t v : p.input_vertex)
      inputs = std::max(inputs, v + 1);
  // Made vertices: one per distinct point (a representative part's copy:
  // every part holding a made vertex made it, so its parents are there).
  struct Made {
    int part;
    VertexId v;
  };
  std::vector<Made> made;
  for (int p = 0; p < d.size; ++p)
    for (std::size_t v = parts[std::size_t(p)].input_vertex.size();
         v < parts[std::size_t(p)].coords.size() / std::size_t(dim); ++v)
      made.push_back({p, VertexId(v)});
  auto point = [&](const Made &x) {
    return parts[std::size_t(x.part)].coords.data() + std::size_t(x.v) * std::size_t(dim);
  };
  std::sort(made.begin(), made.end(), [&](const Made &a, const Made &b) {
    return std::lexicographical_compare(point(a), point(a) + dim, point(b), point(b) + dim);
  });
  std::vector<std::vector<VertexId>> unique_of(std::size_t(d.size)); // part vertex -> unique
  for (int p = 0; p < d.size; ++p)
    unique_of[std::size_t(p)].assign(parts[std::size_t(p)].coords.size() / std::size_t(dim),
                                     kNoVertex);
  std::vector<Made> unique;
  for (std::size_t i = 0; i < made.size(); ++i) {
    if (i == 0 || !std::equal(point(made[i]), point(made[i]) + dim, point(made[i - 1])))
      unique.push_back(made[i]);
    unique_of[std::size_t(made[i].part)][made[i].v] = VertexId(unique.size() - 1);
  }
  // Their order: by level, then after their parents of the same level (the
  // height: 0 when none is, else one more than the highest), then by
  // coordinates (the order of `unique`). Parents' ids are then smaller, as
  // the tree's arrays in files require.
  const bool tree = !parts[0].parent_edge.empty();
  std::vector<std::uint16_t> level_of(unique.size(), 1);
  std::vector<int> height(unique.size(), tree ? -1 : 0);
  // A made vertex's parents by their coordinates: the part's own where it
  // holds them, else those it was told (parent_points: after a migration a
  // part may lack them); NaN when none is known.
  const std::size_t pw = 2 * std::size_t(dim);
  auto parent_point = [&](int p, VertexId v, int k) -> const double * {
    const Part &part = parts[std::size_t(p)];
    const VertexId a = part.parent_edge[2 * std::size_t(v) + std::size_t(k)];
    if (a != kNoVertex)
      return part.coords.data() + std::size_t(a) * std::size_t(dim);
    if ((std::size_t(v) + 1) * pw <= part.parent_points.size() &&
        !std::isnan(part.parent_points[std::size_t(v) * pw]))
      return part.parent_points.data() + std::size_t(v) * pw + std::size_t(k * dim);
    return nullptr;
  };
  // The made vertex (index in `unique`, sorted by coordinates) at p, or none.
  auto unique_at = [&](const double *p) -> VertexId {
    auto it =
        std::lower_bound(unique.begin(), unique.end(), p, [&](const Made &x, const double *q) {
          return std::lexicographical_compare(point(x), point(x) + dim, q, q + dim);
        });
    if (it == unique.end() || !std::equal(p, p + dim, point(*it)))
      return kNoVertex;
    return VertexId(it - unique.begin());
  };
  auto parent_unique = [&](const Made &x, int k) -> VertexId {
    const double *p = parent_point(x.part, x.v, k);
    return p ? unique_at(p) : kNoVertex;
  };
  if (tree) {
    std::vector<VertexId> up(2 * unique.size());
    for (std::size_t u = 0; u < unique.size(); ++u) {
      level_of[u] = parts[std::size_t(unique[u].part)].level[unique[u].v];
      for (int k = 0; k < 2; ++k)
        up[2 * u + std::size_t(k)] = parent_unique(unique[u], k);
    }
    HeightProblem problem;
    height = parent_heights(up, level_of, 0, false, problem);
    if (problem != HeightProblem::None)
      throw std::logic_error("gather: a vertex made by bisection is its own ancestor");
  }
  std::vector<VertexId> order(unique.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) {
    return level_of[a] != level_of[b] ? level_of[a] < level_of[b] : height[a] < height[b];
  });
  std::vector<VertexId> g_of_unique(unique.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    g_of_unique[order[i]] = VertexId(inputs + i);
  std::vector<std::vector<VertexId>> id_in_g(std::size_t(d.size));
  std::vector<std::pair<int, VertexId>> source(inputs, {-1, 0}); // g vertex -> a part's vertex
  for (int p = 0; p < d.size; ++p) {
    const Part &part = parts[std::size_t(p)];
    id_in_g[std::size_t(p)].assign(part.coords.size() / std::size_t(dim), kNoVertex);
    for (std::size_t v = 0; v < part.input_vertex.size(); ++v) {
      id_in_g[std::size_t(p)][v] = VertexId(part.input_vertex[v]);
      source[part.input_vertex[v]] = {p, VertexId(v)};
    }
    for (std::size_t v = part.input_vertex.size(); v < id_in_g[std::size_t(p)].size(); ++v)
      id_in_g[std::size_t(p)][v] = g_of_unique[unique_of[std::size_t(p)][v]];
  }
  for (VertexId u : order)
    source.push_back({unique[u].part, unique[u].v});
  if (tree) {
    g.parent_edge.assign(2 * source.size(), kNoVertex);
    g.level.assign(source.size(), 0);
    for (std::size_t v = 0; v < inputs && v < d.input_level.size(); ++v) {
      g.parent_edge[2 * v] = d.input_parent_edge[2 * v];
      g.parent_edge[2 * v + 1] = d.input_parent_edge[2 * v + 1];
      g.level[v] = d.input_level[v];
    }
    // (resolved once the coordinates are in g, below)
  }
  g.coords.resize(source.size() * std::size_t(dim), 0.0);
  for (std::size_t v = 0; v < source.size(); ++v)
    if (source[v].first >= 0) {
      const Part &part = parts[std::size_t(source[v].first)];
      std::copy_n(part.coords.data() + std::size_t(source[v].second) * dim, dim,
                  g.coords.data() + v * std::size_t(dim));
    }
  if (tree) {
    // Made vertices' parents by coordinates, among g's vertices.
    PointIndex at(g.coords, dim);
    for (std::size_t v = 0; v < source.size(); ++v)
      if (source[v].first >= 0)
        at.add(VertexId(v));
    for (std::size_t v = inputs; v < source.size(); ++v) {
      const auto [p, lv] = source[v];
      g.level[v] = parts[std::size_t(p)].level[lv];
      for (int k = 0; k < 2; ++k) {
        const double *q = parent_point(p, lv, k);
        const VertexId e = q ? at.find(q) : kNoVertex;
        if (e == kNoVertex)
          throw std::logic_error(
              "gather: the parents of a vertex made by bisection are in no part");
        g.parent_edge[2 * v + std::size_t(k)] = e;
      }
      // Parts may have made it from either end first: smaller id first.
      if (g.parent_edge[2 * v] > g.parent_edge[2 * v + 1])
        std::swap(g.parent_edge[2 * v], g.parent_edge[2 * v + 1]);
    }
    // Input vertices whose tree the root was not given (the parts were read
    // from a .pvtu's pieces, read_pvtu_parts): from the parts, by
    // coordinates; an input vertex made by bisection has its parents among
    // the input vertices.
    for (std::size_t v = d.input_level.size(); v < inputs; ++v) {
      const auto [p, lv] = source[v];
      if (p < 0)
        continue;
      const double *q[2] = {parent_point(p, lv, 0), parent_point(p, lv, 1)};
      if (!q[0] || !q[1])
        continue; // an original vertex
      g.level[v] = parts[std::size_t(p)].level[lv];
      for (int k = 0; k < 2; ++k) {
        const VertexId e = at.find(q[k]);
        if (e == kNoVertex || e >= v)
          throw std::logic_error("gather: the parents of an input vertex made by bisection are "
                                 "no earlier input vertices");
        g.parent_edge[2 * v + std::size_t(k)] = e;
      }
      if (g.parent_edge[2 * v] > g.parent_edge[2 * v + 1])
        std::swap(g.parent_edge[2 * v], g.parent_edge[2 * v + 1]);
    }
  }
  for (std::size_t a = 0; a < m.point_data.size(); ++a) {
    DataArray out = parts[0].point_data[a];
    const std::size_t k = std::size_t(out.components);
    out.values.assign(source.size() * k, 0.0);
    for (std::size_t v = 0; v < source.size(); ++v)
      if (source[v].first >= 0) {
        const DataArray &in = parts[std::size_t(source[v].first)].point_data[a];
        std::copy_n(in.values.data() + std::size_t(source[v].second) * k, k,
                    out.values.data() + v * k);
      }
    g.point_data.push_back(std::move(out));
  }
  // Cells by their sorted ids in g.
  struct CellRef {
    std::array<VertexId, 5> key;
    int part;
    CellId c;
  };
  std::vector<CellRef> refs;
  for (int p = 0; p < d.size; ++p) {
    const Part &part = parts[std::size_t(p)];
    for (std::size_t c = 0; c < part.stage.size(); ++c) {
      CellRef ref{{}, p, CellId(c)};
      ref.key.fill(0);
      for (int i = 0; i < n; ++i)
        ref.key[std::size_t(i)] = id_in_g[std::size_t(p)][part.cells[c * std::size_t(n) + i]];
      std::sort(ref.key.begin(), ref.key.begin() + n);
      refs.push_back(ref);
    }
  }
  std::sort(refs.begin(), refs.end(),
            [](const CellRef &a, const CellRef &b) { return a.key < b.key; });
  for (const DataArray &a : parts[0].cell_data)
    g.cell_data.push_back({a.name, a.components, {}, a.type});
  for (const CellRef &ref : refs) {
    const Part &part = parts[std::size_t(ref.part)];
    for (int i = 0; i < n; ++i)
      g.cells.push_back(id_in_g[std::size_t(ref.part)][part.cells[ref.c * std::size_t(n) + i]]);
    g.stage.push_back(Stage(part.stage[ref.c]));
    g.tag.push_back(part.tag[ref.c]);
    if (tree)
      g.generation.push_back(part.generation[ref.c]);
    for (std::size_t a = 0; a < g.cell_data.size(); ++a) {
      const DataArray &in = part.cell_data[a];
      const std::size_t k = std::size_t(in.components);
      g.cell_data[a].values.insert(g.cell_data[a].values.end(), in.values.begin() + ref.c * k,
                                   in.values.begin() + (ref.c + 1) * k);
    }
  }
  // Entities by their sorted ids in g; one on the border of two parts is
  // in both, and kept from the lowest (with its multiplicity there).
  for (std::size_t b = 0; b < m.entities.size(); ++b) {
    Entities block;
    block.dim = m.entities[b].dim;
    for (const DataArray &a : parts[0].entities[b].data)
      block.data.push_back({a.name, a.components, {}, a.type});
    struct EntityRef {
      FaceKey key;
      int part;
      std::size_t i;
    };
    std::vector<EntityRef> erefs;
    for (int p = 0; p < d.size; ++p) {
      const Entities &e = parts[std::size_t(p)].entities[b];
      for (std::size_t i = 0; i < e.size(); ++i) {
        VertexId ids[4];
        for (int k = 0; k <= e.dim; ++k)
          ids[k] = id_in_g[std::size_t(p)][e.entity(i)[k]];
        erefs.push_back({face_key(ids, e.dim + 1), p, i});
      }
    }
    std::stable_sort(erefs.begin(), erefs.end(), [](const EntityRef &x, const EntityRef &y) {
      return x.key.ids != y.key.ids ? x.key.ids < y.key.ids : x.part < y.part;
    });
    int first_part = -1;
    for (std::size_t j = 0; j < erefs.size(); ++j) {
      const EntityRef &ref = erefs[j];
      if (j == 0 || !(erefs[j - 1].key == ref.key))
        first_part = ref.part;
      if (ref.part != first_part)
        continue; // another part's copy of an entity on a border
      const Entities &e = parts[std::size_t(ref.part)].entities[b];
      for (int k = 0; k <= e.dim; ++k)
        block.vertices.push_back(id_in_g[std::size_t(ref.part)][e.entity(ref.i)[k]]);
      for (std::size_t a = 0; a < block.data.size(); ++a) {
        const std::size_t k = std::size_t(e.data[a].components);
        block.data[a].values.insert(block.data[a].values.end(),
                                    e.data[a].values.begin() + ref.i * k,
                                    e.data[a].values.begin() + (ref.i + 1) * k);
      }
    }
    g.entities.push_back(std::move(block));
  }
  return g;
}

DistributedRefineResult refine_marked(DistributedMesh &d, const std::vector<CellId> &marked,
                                      int depth, const RefineLimits &limits) {
  if (depth <= 1)
    return refine(d, marked, limits);
  // As refine_marked (driver.hpp): each marked cell's volume travels to its
  // descendants as a cell array; a descendant fewer than `depth`
  // generations down (by the volume ratio) is bisected again next round.
  Mesh &m = d.local;
  constexpr const char *kAncestor = "bisect:ancestor_volume";
  auto volume = [&](CellId c) {
    double pts[5 * 4];
    cell_points(m, c, pts);
    return std::abs(signed_volume(pts, m.dim));
  };
  m.cell_data.push_back({kAncestor, 1, std::vector<double>(m.num_cells(), 0.0)});
  for (CellId c : marked)
    m.cell_data.back().values.at(c) = volume(c);
  DistributedRefineResult total;
  std::vector<CellId> round = marked;
  for (int r = 0; r < depth && any_rank(!round.empty(), d.comm.get()); ++r) {
    const DistributedRefineResult step = refine(d, round, limits);
    if (r == 0)
      total.selected = step.selected;
    total.bisections += step.bisections;
    total.rounds += step.rounds;
    total.edges_sent += step.edges_sent;
    total.exchange_seconds += step.exchange_seconds;
    total.precision_reached |= step.precision_reached;
    if (step.precision_reached)
      break;
    round.clear();
    const DataArray &anc = *std::find_if(m.cell_data.begin(), m.cell_data.end(),
                                         [&](const DataArray &a) { return a.name == kAncestor; });
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      if (anc.values[c] > 0 && std::lround(std::log2(anc.values[c] / volume(CellId(c)))) < depth)
        round.push_back(CellId(c));
  }
  std::erase_if(m.cell_data, [&](const DataArray &a) { return a.name == kAncestor; });
  return total;
}

// ---------------------------------------------------------------- balance

double imbalance(const DistributedMesh &d) {
  const std::uint64_t mine = d.local.num_cells();
  std::uint64_t largest = 0, total = 0;
  MPI_Allreduce(&mine, &largest, 1, MPI_UINT64_T, MPI_MAX, d.comm.get());
  MPI_Allreduce(&mine, &total, 1, MPI_UINT64_T, MPI_SUM, d.comm.get());
  return total ? double(largest) * double(d.size) / double(total) : 1.0;
}

namespace {

// The Hilbert key of each cell's centroid in the bounding box of all parts.
std::vector<std::uint64_t> hilbert_keys(const DistributedMesh &d) {
  const Mesh &m = d.local;
  const int dim = m.dim, bits = std::min(21, 64 / dim);
  std::vector<double> lo(std::size_t(dim), std::numeric_limits<double>::infinity()),
      hi(std::size_t(dim), -std::numeric_limits<double>::infinity());
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    for (int k = 0; k < dim; ++k) {
      lo[std::size_t(k)] = std::min(lo[std::size_t(k)], m.point(VertexId(v))[k]);
      hi[std::size_t(k)] = std::max(hi[std::size_t(k)], m.point(VertexId(v))[k]);
    }
  MPI_Allreduce(MPI_IN_PLACE, lo.data(), dim, MPI_DOUBLE, MPI_MIN, d.comm.get());
  MPI_Allreduce(MPI_IN_PLACE, hi.data(), dim, MPI_DOUBLE, MPI_MAX, d.comm.get());
  const double scale = double((std::uint64_t(1) << bits) - 1);
  std::vector<std::uint64_t> keys(m.num_cells());
  for (std::size_t c = 0; c < keys.size(); ++c) {
    std::uint32_t x[4];
    for (int k = 0; k < dim; ++k) {
      double sum = 0;
      for (int i = 0; i <= dim; ++i)
        sum += m.point(m.cell(CellId(c))[i])[k];
      const double ext = hi[std::size_t(k)] - lo[std::size_t(k)];
      const double u = ext > 0 ? (sum / (dim + 1) - lo[std::size_t(k)]) / ext : 0.0;
      x[k] = std::uint32_t(std::clamp(u, 0.0, 1.0) * scale);
    }
    keys[c] = hilbert_index(x, dim, bits);
  }
  return keys;
}

// The rank each cell goes to: equal stretches of all parts' cells along the
// curve, ties by rank and cell id (so stretches are exact even where many
// centroids share a key). Splitters by bisection of the (key, rank, cell)
// range, counting below each with an all-reduce (129 rounds of P - 1
// counts).
std::vector<int> hilbert_destinations(const DistributedMesh &d) {
  using Key = unsigned __int128;
  const std::vector<std::uint64_t> hk = hilbert_keys(d);
  std::vector<Key> keys(hk.size());
  for (std::size_t c = 0; c < hk.size(); ++c)
    keys[c] = Key(hk[c]) << 64 | Key(std::uint64_t(d.rank) << 40 | std::uint64_t(c));
  std::vector<Key> sorted = keys;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t splits = std::size_t(d.size) - 1;
  std::uint64_t total = sorted.size();
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_UINT64_T, MPI_SUM, d.comm.get());
  // lo[s]: the smallest key with at least target(s) keys below it.
  std::vector<Key> lo(splits, 0), hi(splits, ~Key(0));
  std::vector<std::uint64_t> below(splits);
  for (int round = 0; round < 129; ++round) {
    for (std::size_t s = 0; s < splits; ++s) {
      const Key mid = lo[s] + (hi[s] - lo[s]) / 2;
      below[s] =
          std::uint64_t(std::lower_bound(sorted.begin(), sorted.end(), mid) - sorted.begin());
    }
    MPI_Allreduce(MPI_IN_PLACE, below.data(), int(splits), MPI_UINT64_T, MPI_SUM, d.comm.get());
    for (std::size_t s = 0; s < splits; ++s) {
      const Key mid = lo[s] + (hi[s] - lo[s]) / 2;
      const std::uint64_t target = total * (s + 1) / std::uint64_t(d.size);
      if (below[s] >= target)
        hi[s] = mid;
      else
        lo[s] = mid + (mid < hi[s]);
    }
  }
  std::vector<int> dest(keys.size());
  for (std::size_t c = 0; c < keys.size(); ++c)
    dest[c] = int(std::upper_bound(lo.begin(), lo.end(), keys[c]) - lo.begin());
  return dest;
}

// Moves each local cell c to rank dest[c], with its vertices, bisection
// state, tree, tags and data; the parts' vertices are known by their
// coordinates, and who shares which is found again through a directory:
// each vertex has a home rank (a hash of its coordinates) that hears from
// every rank holding it and tells each of them the others. Collective.
// `with_tree`: whether the parts carry the tree (-1: this part says, by
// has_tree(); a part without cells cannot).
void migrate(DistributedMesh &d, const std::vector<int> &dest, int with_tree = -1) {
  const Mesh &m = d.local;
  const int dim = m.dim, n = m.cell_size(), P = d.size;
  const std::size_t np = static_cast<std::size_t>(P);
  const std::size_t pw = 2 * std::size_t(dim);
  const bool tree = with_tree < 0 ? m.has_tree() : with_tree != 0;
  const std::size_t nv = m.num_vertices();
  MPI_Comm comm = d.comm.get();
  // Each vertex's parents by coordinates (NaN: none known).
  auto parents_of = [&](VertexId v, double *out) {
    std::fill(out, out + pw, std::numeric_limits<double>::quiet_NaN());
    if (!tree)
      return;
    const VertexId a = m.parent_edge[2 * std::size_t(v)], b = m.parent_edge[2 * std::size_t(v) + 1];
    if (a != kNoVertex) {
      std::copy_n(m.point(a), dim, out);
      std::copy_n(m.point(b), dim, out + dim);
    } else if ((std::size_t(v) + 1) * pw <= d.parent_points.size()) {
      std::copy_n(d.parent_points.data() + std::size_t(v) * pw, pw, out);
    }
  };
  std::vector<std::unordered_multimap<FaceKey, std::uint64_t, FaceKeyHash>> entity_index(
      m.entities.size());
  for (std::size_t b = 0; b < m.entities.size(); ++b)
    for (std::size_t i = 0; i < m.entities[b].size(); ++i)
      entity_index[b].emplace(face_key(m.entities[b].entity(i), m.entities[b].dim + 1), i);
  std::vector<std::vector<std::uint64_t>> cells_to(np);
  for (std::size_t c = 0; c < dest.size(); ++c)
    cells_to[std::size_t(dest[c])].push_back(c);
  std::vector<VertexId> local_id(nv, kNoVertex);
  std::vector<char> sendbuf;
  std::vector<long long> send_counts(np), send_displs(np);
  for (int r = 0; r < P; ++r) {
    const std::vector<std::uint64_t> &cells = cells_to[std::size_t(r)];
    std::vector<std::uint64_t> verts;
    for (std::uint64_t c : cells)
      for (int i = 0; i < n; ++i)
        verts.push_back(m.cell(CellId(c))[i]);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    for (std::size_t i = 0; i < verts.size(); ++i)
      local_id[verts[i]] = VertexId(i);
    Writer w;
    std::vector<double> coords, parents(verts.size() * pw);
    std::vector<std::uint64_t> ids;
    std::vector<std::uint16_t> level;
    for (std::size_t i = 0; i < verts.size(); ++i) {
      const VertexId v = VertexId(verts[i]);
      coords.insert(coords.end(), m.point(v), m.point(v) + dim);
      ids.push_back(v < d.input_vertex.size() ? d.input_vertex[v] : ~std::uint64_t(0));
      level.push_back(tree && m.level.size() == nv ? m.level[v] : std::uint16_t(0));
      parents_of(v, parents.data() + i * pw);
    }
    w.put(coords);
    w.put(ids);
    w.put(level);
    w.put(parents);
    put_arrays(w, m.point_data, verts);
    std::vector<VertexId> conn;
    std::vector<std::uint8_t> stage, tag;
    std::vector<std::uint16_t> generation;
    for (std::uint64_t c : cells) {
      for (int i = 0; i < n; ++i)
        conn.push_back(local_id[m.cell(CellId(c))[i]]);
      stage.push_back(std::uint8_t(m.stage[c]));
      tag.push_back(m.tag[c]);
      generation.push_back(tree ? m.generation[c] : std::uint16_t(0));
    }
    w.put(conn);
    w.put(stage);
    w.put(tag);
    w.put(generation);
    put_arrays(w, m.cell_data, cells);
    for (std::size_t b = 0; b < m.entities.size(); ++b) {
      const Entities &block = m.entities[b];
      std::vector<std::uint64_t> taken;
      for (std::uint64_t c : cells)
        for_each_face(m.cell(CellId(c)), n, block.dim, [&](const VertexId *f, int count) {
          auto [first, last] = entity_index[b].equal_range(face_key(f, count));
          for (auto it = first; it != last; ++it)
            taken.push_back(it->second);
        });
      std::sort(taken.begin(), taken.end());
      taken.erase(std::unique(taken.begin(), taken.end()), taken.end());
      std::vector<VertexId> evs;
      for (std::uint64_t i : taken)
        for (int k = 0; k <= block.dim; ++k)
          evs.push_back(local_id[block.entity(i)[k]]);
      w.put(evs);
      put_arrays(w, block.data, taken);
    }
    for (std::uint64_t v : verts)
      local_id[v] = kNoVertex;
    send_displs[std::size_t(r)] = (long long)sendbuf.size();
    send_counts[std::size_t(r)] = (long long)w.bytes.size();
    sendbuf.insert(sendbuf.end(), w.bytes.begin(), w.bytes.end());
  }
  // The messages: sizes, then bytes (point to point, any size).
  std::vector<long long> recv_counts(np);
  MPI_Alltoall(send_counts.data(), 1, MPI_LONG_LONG, recv_counts.data(), 1, MPI_LONG_LONG, comm);
  std::vector<std::vector<char>> in(np);
  {
    std::vector<MPI_Request> requests;
    for (int r = 0; r < P; ++r) {
      in[std::size_t(r)].resize(std::size_t(recv_counts[std::size_t(r)]));
      for (std::size_t at = 0; at < in[std::size_t(r)].size(); at += kChunk) {
        requests.emplace_back();
        MPI_Irecv(in[std::size_t(r)].data() + at,
                  int(std::min(kChunk, in[std::size_t(r)].size() - at)), MPI_CHAR, r, 3, comm,
                  &requests.back());
      }
    }
    for (int r = 0; r < P; ++r)
      for (std::size_t at = 0; at < std::size_t(send_counts[std::size_t(r)]); at += kChunk) {
        requests.emplace_back();
        MPI_Isend(sendbuf.data() + send_displs[std::size_t(r)] + at,
                  int(std::min(kChunk, std::size_t(send_counts[std::size_t(r)]) - at)), MPI_CHAR, r,
                  3, comm, &requests.back());
      }
    MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  }
  std::vector<char>().swap(sendbuf);

  // The new part: vertices merged by coordinates.
  Mesh out;
  out.dim = dim;
  out.marking = m.marking;
  out.physical_names = m.physical_names;
  for (const DataArray &a : m.point_data)
    out.point_data.push_back({a.name, a.components, {}, a.type});
  for (const DataArray &a : m.cell_data)
    out.cell_data.push_back({a.name, a.components, {}, a.type});
  std::vector<double> coords;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint16_t> level;
  std::vector<double> parents;
  PointIndex index(coords, dim);
  std::vector<Entities> entities(m.entities.size());
  std::vector<std::unordered_map<FaceKey, int, FaceKeyHash>> entity_from(m.entities.size());
  for (std::size_t b = 0; b < m.entities.size(); ++b) {
    entities[b].dim = m.entities[b].dim;
    for (const DataArray &a : m.entities[b].data)
      entities[b].data.push_back({a.name, a.components, {}, a.type});
  }
  for (int r = 0; r < P; ++r) {
    Reader rd(in[std::size_t(r)]);
    const std::vector<double> c = rd.get_vector<double>();
    const std::vector<std::uint64_t> id = rd.get_vector<std::uint64_t>();
    const std::vector<std::uint16_t> lv = rd.get_vector<std::uint16_t>();
    const std::vector<double> pa = rd.get_vector<double>();
    const std::vector<DataArray> pd = get_arrays(rd);
    std::vector<VertexId> to(id.size());
    for (std::size_t i = 0; i < id.size(); ++i) {
      const VertexId v = VertexId(coords.size() / std::size_t(dim));
      coords.insert(coords.end(), c.begin() + std::ptrdiff_t(i * dim),
                    c.begin() + std::ptrdiff_t((i + 1) * dim));
      const VertexId w = index.add(v);
      to[i] = w;
      if (w != v) {
        coords.resize(coords.size() - std::size_t(dim));
        continue;
      }
      ids.push_back(id[i]);
      level.push_back(lv[i]);
      parents.insert(parents.end(), pa.begin() + std::ptrdiff_t(i * pw),
                     pa.begin() + std::ptrdiff_t((i + 1) * pw));
      for (std::size_t a = 0; a < pd.size(); ++a) {
        const std::size_t k = std::size_t(pd[a].components);
        out.point_data[a].values.insert(out.point_data[a].values.end(),
                                        pd[a].values.begin() + std::ptrdiff_t(i * k),
                                        pd[a].values.begin() + std::ptrdiff_t((i + 1) * k));
      }
    }
    for (VertexId x : rd.get_vector<VertexId>())
      out.cells.push_back(to[x]);
    for (std::uint8_t st : rd.get_vector<std::uint8_t>())
      out.stage.push_back(Stage(st));
    const std::vector<std::uint8_t> tg = rd.get_vector<std::uint8_t>();
    out.tag.insert(out.tag.end(), tg.begin(), tg.end());
    const std::vector<std::uint16_t> gen = rd.get_vector<std::uint16_t>();
    out.generation.insert(out.generation.end(), gen.begin(), gen.end());
    const std::vector<DataArray> cd = get_arrays(rd);
    for (std::size_t a = 0; a < cd.size(); ++a)
      out.cell_data[a].values.insert(out.cell_data[a].values.end(), cd[a].values.begin(),
                                     cd[a].values.end());
    for (std::size_t b = 0; b < m.entities.size(); ++b) {
      const std::vector<VertexId> evs = rd.get_vector<VertexId>();
      const std::vector<DataArray> ed = get_arrays(rd);
      const int k = entities[b].dim + 1;
      for (std::size_t i = 0; i * std::size_t(k) < evs.size(); ++i) {
        VertexId f[4];
        for (int j = 0; j < k; ++j)
          f[j] = to[evs[i * std::size_t(k) + std::size_t(j)]];
        // An entity on the border of two senders comes from both: the
        // first sender's copies are kept.
        const int from = entity_from[b].emplace(face_key(f, k), r).first->second;
        if (from != r)
          continue;
        entities[b].vertices.insert(entities[b].vertices.end(), f, f + k);
        for (std::size_t a = 0; a < ed.size(); ++a) {
          const std::size_t w = std::size_t(ed[a].components);
          entities[b].data[a].values.insert(entities[b].data[a].values.end(),
                                            ed[a].values.begin() + std::ptrdiff_t(i * w),
                                            ed[a].values.begin() + std::ptrdiff_t((i + 1) * w));
        }
      }
    }
  }
  in.clear();
  const std::size_t count = ids.size();
  // Parents found here, by coordinates.
  std::vector<VertexId> parent(2 * count, kNoVertex);
  for (std::size_t v = 0; v < count && tree; ++v) {
    const double *p = parents.data() + v * pw;
    if (std::isnan(p[0]))
      continue;
    const VertexId a = index.find(p), b = index.find(p + dim);
    if (a != kNoVertex && b != kNoVertex) {
      parent[2 * v] = a;
      parent[2 * v + 1] = b;
    }
  }
  // The order: input vertices by their input id, then the made ones by
  // level, then after their parents of the same level, then as received.
  std::vector<int> height(count, 0);
  if (tree) {
    HeightProblem problem;
    height = parent_heights(parent, level, 0, false, problem);
    if (problem != HeightProblem::None)
      throw std::logic_error("rebalance: a vertex is its own ancestor");
  }
  std::vector<VertexId> order(count);
  std::iota(order.begin(), order.end(), VertexId(0));
  const std::uint64_t none = ~std::uint64_t(0);
  std::stable_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) {
    const bool ia = ids[a] != none, ib = ids[b] != none;
    if (ia != ib)
      return ia;
    if (ia)
      return ids[a] < ids[b];
    return level[a] != level[b] ? level[a] < level[b] : height[a] < height[b];
  });
  std::vector<VertexId> id_of(count);
  for (std::size_t i = 0; i < count; ++i)
    id_of[order[i]] = VertexId(i);
  out.coords.resize(coords.size());
  for (std::size_t i = 0; i < count; ++i)
    std::copy_n(coords.data() + std::size_t(order[i]) * dim, dim,
                out.coords.data() + i * std::size_t(dim));
  for (DataArray &a : out.point_data) {
    const std::size_t k = std::size_t(a.components);
    std::vector<double> values(a.values.size());
    for (std::size_t i = 0; i < count; ++i)
      std::copy_n(a.values.data() + std::size_t(order[i]) * k, k, values.data() + i * k);
    a.values = std::move(values);
  }
  for (VertexId &x : out.cells)
    x = id_of[x];
  for (Entities &block : entities)
    for (VertexId &x : block.vertices)
      x = id_of[x];
  out.entities = std::move(entities);
  d.input_vertex.clear();
  for (std::size_t i = 0; i < count && ids[order[i]] != none; ++i)
    d.input_vertex.push_back(ids[order[i]]);
  d.parent_points.clear();
  if (tree) {
    out.parent_edge.assign(2 * count, kNoVertex);
    out.level.resize(count);
    d.parent_points.resize(count * pw);
    for (std::size_t i = 0; i < count; ++i) {
      const VertexId v = order[i];
      out.level[i] = level[v];
      std::copy_n(parents.data() + std::size_t(v) * pw, pw, d.parent_points.data() + i * pw);
      if (parent[2 * std::size_t(v)] != kNoVertex) {
        out.parent_edge[2 * i] = id_of[parent[2 * std::size_t(v)]];
        out.parent_edge[2 * i + 1] = id_of[parent[2 * std::size_t(v) + 1]];
      }
    }
  } else {
    out.generation.clear();
  }
  d.local = std::move(out);

  // Who else holds each vertex: a directory, each vertex at the home rank
  // its coordinates hash to.
  const Mesh &nm = d.local;
  auto home = [&](const double *p) { return home_rank(p, dim, P); };
  std::vector<std::vector<double>> ask(np);
  std::vector<std::vector<VertexId>> asked(np);
  for (std::size_t v = 0; v < nm.num_vertices(); ++v) {
    const int h = home(nm.point(VertexId(v)));
    ask[std::size_t(h)].insert(ask[std::size_t(h)].end(), nm.point(VertexId(v)),
                               nm.point(VertexId(v)) + dim);
    asked[std::size_t(h)].push_back(VertexId(v));
  }
  std::vector<std::vector<double>> heard = all_to_all(ask, comm);
  // At home: every point heard, with the ranks that hold it.
  std::map<std::vector<double>, std::vector<int>> holders;
  for (int r = 0; r < P; ++r)
    for (std::size_t at = 0; at < heard[std::size_t(r)].size(); at += std::size_t(dim))
      holders[std::vector<double>(heard[std::size_t(r)].begin() + std::ptrdiff_t(at),
                                  heard[std::size_t(r)].begin() + std::ptrdiff_t(at + dim))]
          .push_back(r);
  // Replies, in the order asked: a count, then the other holders.
  std::vector<std::vector<int>> reply(np);
  for (int r = 0; r < P; ++r)
    for (std::size_t at = 0; at < heard[std::size_t(r)].size(); at += std::size_t(dim)) {
      const std::vector<int> &hs =
          holders[std::vector<double>(heard[std::size_t(r)].begin() + std::ptrdiff_t(at),
                                      heard[std::size_t(r)].begin() + std::ptrdiff_t(at + dim))];
      reply[std::size_t(r)].push_back(int(hs.size()) - 1);
      for (int q : hs)
        if (q != r)
          reply[std::size_t(r)].push_back(q);
    }
  heard.clear();
  holders.clear();
  const std::vector<std::vector<int>> answers = all_to_all(reply, comm, MPI_INT);
  d.sharers.assign(nm.num_vertices(), {});
  for (int h = 0; h < P; ++h) {
    std::size_t at = 0;
    for (const VertexId v : asked[std::size_t(h)]) {
      const int k = answers[std::size_t(h)][at++];
      d.sharers[v].assign(answers[std::size_t(h)].begin() + std::ptrdiff_t(at),
                          answers[std::size_t(h)].begin() + std::ptrdiff_t(at + std::size_t(k)));
      std::sort(d.sharers[v].begin(), d.sharers[v].end());
      at += std::size_t(k);
    }
  }
  std::vector<int> nb;
  for (const std::vector<int> &s : d.sharers)
    nb.insert(nb.end(), s.begin(), s.end());
  std::sort(nb.begin(), nb.end());
  nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  d.neighbours = nb;
  MPI_Comm graph;
  MPI_Dist_graph_create_adjacent(comm, int(nb.size()), nb.empty() ? MPI_WEIGHTS_EMPTY : nb.data(),
                                 MPI_UNWEIGHTED, int(nb.size()),
                                 nb.empty() ? MPI_WEIGHTS_EMPTY : nb.data(), MPI_UNWEIGHTED,
                                 MPI_INFO_NULL, 0, &graph);
  d.graph = Communicator(graph);
  count_global(d);
}

} // namespace

bool rebalance(DistributedMesh &d, const Invariants &part_original, double border_original,
               double tolerance) {
  if (d.size == 1 || imbalance(d) <= 1 + tolerance || d.local.marking == Marking::Explicit)
    return false;
  // What moves is checked first (the parts' own checks start again from
  // the new parts).
  const CheckResult check = check_refined(d, part_original, border_original);
  if (!check.ok)
    throw CheckError("internal check failed before rebalancing: " + check.failure +
                     "; no output written");
  migrate(d, hilbert_destinations(d));
  return true;
}

// ---------------------------------------------------------------- reading

namespace {

// The lowest failing rank's error (a message and its kind), thrown on every
// rank; nothing when no rank failed. Collective.
void throw_first(const std::string &failure, ErrorKind kind, const DistributedMesh &d) {
  const Failure f = first_failure(failure, d.rank, d.size, d.comm.get());
  if (f.rank == d.size)
    return;
  int k = int(kind);
  MPI_Bcast(&k, 1, MPI_INT, f.rank, d.comm.get());
  throw Error(ErrorKind(k), {}, f.message);
}

// Runs `step`, keeping its error (message and kind) for throw_first.
template <class F> void keep_failure(std::string &failure, ErrorKind &kind, F &&step) {
  try {
    step();
  } catch (const Error &e) {
    failure = e.what();
    kind = e.kind;
  } catch (const std::bad_alloc &) {
    failure = "out of memory reading the pieces";
    kind = ErrorKind::Resource;
  } catch (const std::exception &e) {
    failure = e.what();
    kind = ErrorKind::Check;
  }
}

// Takes the array `name` out of `arrays` (its values; empty when absent).
std::optional<DataArray> take_array(std::vector<DataArray> &arrays, const char *name) {
  for (auto it = arrays.begin(); it != arrays.end(); ++it)
    if (it->name == name) {
      DataArray a = std::move(*it);
      arrays.erase(it);
      return a;
    }
  return std::nullopt;
}

std::vector<DataArray> empty_like(const std::vector<DataArray> &arrays) {
  std::vector<DataArray> out;
  for (const DataArray &a : arrays)
    out.push_back({a.name, a.components, {}, a.type});
  return out;
}

// A part as the pieces give it, before migration: per vertex its global id
// (-1: made since the run that wrote the pieces began) and, with the tree,
// its level and parents by coordinates (its own point twice: an original).
struct PiecePart {
  std::vector<double> gid, level, parents, generation;
  std::vector<double> piece; // per cell: its piece's index
  bool tree = false;
  std::string first_piece; // for messages
};

// Loads pieces [first, last) of `sources` into d.local (merged by
// coordinates) and `pp`. Throws Error naming `path`.
void load_pieces(DistributedMesh &d, PiecePart &pp, const std::string &path,
                 const std::vector<std::string> &sources, std::size_t first, std::size_t last,
                 const LoadProgress &progress) {
  Mesh &m = d.local;
  std::optional<PointIndex> index;
  std::vector<std::unordered_set<FaceKey, FaceKeyHash>> kept; // per block: entities taken
  for (std::size_t i = first; i < last; ++i) {
    const std::string &source = sources[i];
    Mesh p;
    try {
      p = load_mesh(source, i == first ? progress : LoadProgress{});
    } catch (const Error &e) {
      throw Error(e.kind, path, "piece " + std::string(e.what()));
    }
    auto refuse = [&](const std::string &why) {
      throw InputError(path, "piece " + source + ": " + why);
    };
    if (!p.marked())
      refuse(
          "carries no bisection state (the bisect:* cell arrays); read the .pvtu without mpirun, "
          "or refine it from one rank");
    if (p.marking == Marking::Explicit)
      refuse("explicit marking (bisect:edge_rank) is read by one rank only; run without mpirun");
    std::optional<DataArray> gid = take_array(p.point_data, kGlobalIdArray);
    std::optional<DataArray> gen = take_array(p.cell_data, kPieceGenerationArray);
    std::optional<DataArray> lev = take_array(p.point_data, kPieceLevelArray);
    std::optional<DataArray> par = take_array(p.point_data, kPieceParentsArray);
    if (!gid || gid->components != 1)
      refuse(std::string("has no one-component point array ") + kGlobalIdArray);
    const bool tree = gen && lev && par;
    if ((gen || lev || par) && !tree)
      refuse(std::string("the tree is incomplete: ") + kPieceGenerationArray + ", " +
             kPieceLevelArray + " and " + kPieceParentsArray + " come together");
    const int dim = p.dim;
    const std::size_t pw = 2 * std::size_t(dim);
    if (tree && (gen->components != 1 || lev->components != 1 || par->components != int(pw)))
      refuse("the tree's bisect:piece_* arrays have the wrong number of components");
    if (i == first) {
      m.dim = dim;
      m.marking = p.marking;
      m.point_data = empty_like(p.point_data);
      m.cell_data = empty_like(p.cell_data);
      m.physical_names = p.physical_names;
      pp.tree = tree;
      pp.first_piece = source;
      index.emplace(m.coords, dim);
    } else if (p.dim != m.dim || p.marking != m.marking || tree != pp.tree ||
               !same_arrays(p.point_data, m.point_data) || !same_arrays(p.cell_data, m.cell_data)) {
      refuse("its dimension, marking, tree or point and cell arrays differ from piece " +
             pp.first_piece + "'s");
    }
    auto whole = [](double x, double hi) {
      return std::isfinite(x) && x >= 0 && x <= hi && x == std::floor(x);
    };
    std::vector<VertexId> to(p.num_vertices());
    for (std::size_t v = 0; v < p.num_vertices(); ++v) {
      const double g = gid->values[v];
      if (!(g == -1 || whole(g, 4294967294.0)))
        refuse(std::string(kGlobalIdArray) + " of point " + std::to_string(v) +
               " is neither -1 nor an id below 2^32 - 1");
      const VertexId nv = VertexId(m.num_vertices());
      m.coords.insert(m.coords.end(), p.point(VertexId(v)), p.point(VertexId(v)) + dim);
      const VertexId w = index->add(nv);
      to[v] = w;
      if (w != nv) {
        m.coords.resize(m.coords.size() - std::size_t(dim));
        if (pp.gid[w] != g)
          refuse("point " + std::to_string(v) + " has another " + kGlobalIdArray +
                 " than the same point in an earlier piece");
        continue;
      }
      pp.gid.push_back(g);
      for (std::size_t a = 0; a < p.point_data.size(); ++a) {
        const std::size_t k = std::size_t(p.point_data[a].components);
        m.point_data[a].values.insert(m.point_data[a].values.end(),
                                      p.point_data[a].values.begin() + std::ptrdiff_t(v * k),
                                      p.point_data[a].values.begin() + std::ptrdiff_t((v + 1) * k));
      }
      if (!tree)
        continue;
      const double level = lev->values[v];
      const double *q = par->values.data() + v * pw;
      const bool self_a = std::equal(q, q + dim, p.point(VertexId(v))),
                 self_b = std::equal(q + dim, q + 2 * dim, p.point(VertexId(v)));
      if (!whole(level, 65535) || (level == 0) != (self_a && self_b) || self_a != self_b)
        refuse(std::string(kPieceLevelArray) + " and " + kPieceParentsArray + " of point " +
               std::to_string(v) +
               " disagree (level 0 is an original vertex, which names itself as both ends)");
      pp.level.push_back(level);
      if (self_a)
        pp.parents.insert(pp.parents.end(), pw, std::numeric_limits<double>::quiet_NaN());
      else
        pp.parents.insert(pp.parents.end(), q, q + pw);
    }
    const int n = p.cell_size();
    for (std::size_t c = 0; c < p.num_cells(); ++c) {
      for (int k = 0; k < n; ++k)
        m.cells.push_back(to[p.cell(CellId(c))[k]]);
      m.stage.push_back(p.stage[c]);
      m.tag.push_back(p.tag[c]);
      if (tree) {
        if (!whole(gen->values[c], 65535))
          refuse(std::string(kPieceGenerationArray) + " of cell " + std::to_string(c) +
                 " is not a count below 2^16");
        pp.generation.push_back(gen->values[c]);
      }
    }
    for (std::size_t a = 0; a < p.cell_data.size(); ++a)
      m.cell_data[a].values.insert(m.cell_data[a].values.end(), p.cell_data[a].values.begin(),
                                   p.cell_data[a].values.end());
    pp.piece.insert(pp.piece.end(), p.num_cells(), double(i));
    // Tagged entities: a block per dimension; one on the border of two
    // pieces is kept once.
    for (const Entities &e : p.entities) {
      std::size_t b = 0;
      while (b < m.entities.size() && m.entities[b].dim != e.dim)
        ++b;
      if (b == m.entities.size()) {
        m.entities.push_back({});
        m.entities.back().dim = e.dim;
        m.entities.back().data = empty_like(e.data);
        kept.emplace_back();
      } else if (!same_arrays(e.data, m.entities[b].data)) {
        refuse("its cells of dimension " + std::to_string(e.dim) +
               " have other arrays than an earlier piece's");
      }
      Entities &block = m.entities[b];
      for (std::size_t i2 = 0; i2 < e.size(); ++i2) {
        VertexId f[4];
        for (int k = 0; k <= e.dim; ++k)
          f[k] = to[e.entity(i2)[k]];
        if (!kept[b].insert(face_key(f, e.dim + 1)).second)
          continue;
        block.vertices.insert(block.vertices.end(), f, f + e.dim + 1);
        for (std::size_t a = 0; a < e.data.size(); ++a) {
          const std::size_t k = std::size_t(e.data[a].components);
          block.data[a].values.insert(block.data[a].values.end(),
                                      e.data[a].values.begin() + std::ptrdiff_t(i2 * k),
                                      e.data[a].values.begin() + std::ptrdiff_t((i2 + 1) * k));
        }
      }
    }
  }
}

// Every rank's layout (dimension, marking, tree, point and cell arrays,
// blocks of tagged entities, physical names) made one: a rank without
// pieces takes the first loaded one's; blocks are the union over all ranks,
// by increasing dimension. Throws on every rank when pieces differ.
void agree_layout(DistributedMesh &d, PiecePart &pp, bool loaded, const std::string &path) {
  Mesh &m = d.local;
  Writer w;
  w.put<std::uint8_t>(loaded);
  w.put<std::int32_t>(m.dim);
  w.put<std::uint8_t>(std::uint8_t(m.marking));
  w.put<std::uint8_t>(pp.tree);
  put_arrays(w, m.point_data, {});
  put_arrays(w, m.cell_data, {});
  w.put<std::uint64_t>(m.entities.size());
  for (const Entities &e : m.entities) {
    w.put<std::int32_t>(e.dim);
    put_arrays(w, e.data, {});
  }
  w.put<std::uint64_t>(m.physical_names.size());
  for (const PhysicalName &pn : m.physical_names) {
    w.put<std::int32_t>(pn.dim);
    w.put<std::int32_t>(pn.tag);
    w.put(pn.name);
  }
  w.put(pp.first_piece);
  int size = int(w.bytes.size());
  std::vector<int> sizes(std::size_t(d.size)), offsets(std::size_t(d.size) + 1, 0);
  MPI_Allgather(&size, 1, MPI_INT, sizes.data(), 1, MPI_INT, d.comm.get());
  for (int r = 0; r < d.size; ++r)
    offsets[std::size_t(r) + 1] = offsets[std::size_t(r)] + sizes[std::size_t(r)];
  std::vector<char> all(std::size_t(offsets.back()));
  MPI_Allgatherv(w.bytes.data(), size, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR,
                 d.comm.get());
  struct Layout {
    bool loaded = false;
    int dim = 0;
    Marking marking = Marking::Index;
    bool tree = false;
    std::vector<DataArray> point, cell;
    std::vector<Entities> blocks;
    std::vector<PhysicalName> names;
    std::string piece;
  };
  std::vector<Layout> layouts(std::size_t(d.size));
  for (int r = 0; r < d.size; ++r) {
    std::vector<char> bytes(all.begin() + offsets[std::size_t(r)],
                            all.begin() + offsets[std::size_t(r) + 1]);
    Reader rd(bytes);
    Layout &l = layouts[std::size_t(r)];
    l.loaded = rd.get<std::uint8_t>();
    l.dim = rd.get<std::int32_t>();
    l.marking = Marking(rd.get<std::uint8_t>());
    l.tree = rd.get<std::uint8_t>();
    l.point = get_arrays(rd);
    l.cell = get_arrays(rd);
    l.blocks.resize(rd.get<std::uint64_t>());
    for (Entities &e : l.blocks) {
      e.dim = rd.get<std::int32_t>();
      e.data = get_arrays(rd);
    }
    l.names.resize(rd.get<std::uint64_t>());
    for (PhysicalName &pn : l.names) {
      pn.dim = rd.get<std::int32_t>();
      pn.tag = rd.get<std::int32_t>();
      pn.name = rd.get_string();
    }
    l.piece = rd.get_string();
  }
  const Layout *model = nullptr;
  for (const Layout &l : layouts)
    if (l.loaded && !model)
      model = &l;
  std::string failure;
  if (loaded &&
      (m.dim != model->dim || m.marking != model->marking || pp.tree != model->tree ||
       !same_arrays(m.point_data, model->point) || !same_arrays(m.cell_data, model->cell)))
    failure = path + ": piece " + pp.first_piece +
              ": its dimension, marking, tree or point and cell arrays differ from piece " +
              model->piece + "'s";
  // The blocks: every dimension some rank has, with the first one's arrays.
  std::map<int, const Entities *> blocks;
  for (const Layout &l : layouts)
    for (const Entities &e : l.blocks)
      blocks.emplace(e.dim, &e);
  for (const Entities &e : m.entities)
    if (failure.empty() && !same_arrays(e.data, blocks.at(e.dim)->data))
      failure = path + ": piece " + pp.first_piece + ": its cells of dimension " +
                std::to_string(e.dim) + " have other arrays than another piece's";
  throw_first(failure, ErrorKind::Input, d);
  if (!loaded) {
    m.dim = model->dim;
    m.marking = model->marking;
    m.point_data = empty_like(model->point);
    m.cell_data = empty_like(model->cell);
    m.physical_names = model->names;
    pp.tree = model->tree;
  }
  std::vector<Entities> ordered;
  for (const auto &[dim, e] : blocks) {
    auto own = std::find_if(m.entities.begin(), m.entities.end(),
                            [&](const Entities &x) { return x.dim == dim; });
    if (own != m.entities.end()) {
      ordered.push_back(std::move(*own));
    } else {
      ordered.push_back({});
      ordered.back().dim = dim;
      ordered.back().data = empty_like(e->data);
    }
  }
  m.entities = std::move(ordered);
}

// Input vertices (a global id) first, by id, then the others as they are;
// d.input_vertex, and the tree's arrays from the pieces' (parents by
// coordinates, found after migrating). Throws InputError when an id names
// two points.
void order_part(DistributedMesh &d, PiecePart &pp, const std::string &path) {
  Mesh &m = d.local;
  const std::size_t nv = m.num_vertices(), dim = std::size_t(m.dim), pw = 2 * dim;
  std::vector<VertexId> order(nv);
  std::iota(order.begin(), order.end(), VertexId(0));
  std::stable_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) {
    const bool ia = pp.gid[a] >= 0, ib = pp.gid[b] >= 0;
    if (ia != ib)
      return ia;
    return ia && pp.gid[a] < pp.gid[b];
  });
  for (std::size_t i = 1; i < nv; ++i)
    if (pp.gid[order[i]] >= 0 && pp.gid[order[i]] == pp.gid[order[i - 1]])
      throw InputError(path, std::string(kGlobalIdArray) + " " +
                                 std::to_string(std::uint64_t(pp.gid[order[i]])) +
                                 " names two points");
  reorder_vertices(m, order);
  d.input_vertex.clear();
  for (std::size_t i = 0; i < nv && pp.gid[order[i]] >= 0; ++i)
    d.input_vertex.push_back(std::uint64_t(pp.gid[order[i]]));
  if (pp.tree) {
    m.generation.assign(pp.generation.begin(), pp.generation.end());
    m.level.resize(nv);
    d.parent_points.resize(nv * pw);
    for (std::size_t i = 0; i < nv; ++i) {
      m.level[i] = std::uint16_t(pp.level[order[i]]);
      std::copy_n(pp.parents.data() + order[i] * pw, pw, d.parent_points.data() + i * pw);
    }
    m.parent_edge.assign(2 * nv, kNoVertex);
  }
}

// The tree the pieces name (before migration: d.parent_points, m.level):
// each made vertex the midpoint of its parent edge (within 1e-6 of the
// edge's extent, as decode_tree asks of a .vtu), both ends points of some
// piece, neither of a higher level. Each point is registered at its home
// rank, which answers the queries for parents. Throws on every rank.
void check_piece_tree(const DistributedMesh &d, const std::string &path) {
  const Mesh &m = d.local;
  const int dim = m.dim;
  const std::size_t pw = 2 * std::size_t(dim), np = std::size_t(d.size);
  std::string failure;
  std::vector<std::vector<double>> reg(np), ask(np);
  std::vector<std::vector<std::size_t>> asked(np); // the made vertex of each query
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const double *z = m.point(VertexId(v));
    std::vector<double> &r = reg[std::size_t(home_rank(z, dim, d.size))];
    r.insert(r.end(), z, z + dim);
    r.push_back(m.level[v]);
    const double *pq = d.parent_points.data() + v * pw;
    if (std::isnan(pq[0]))
      continue;
    double extent = 0, off = 0;
    for (int k = 0; k < dim; ++k) {
      extent = std::max(extent, std::abs(pq[k] - pq[dim + k]));
      off = std::max(off, std::abs(z[k] - 0.5 * (pq[k] + pq[dim + k])));
    }
    if (!(off <= 1e-6 * extent) && failure.empty())
      failure = path + ": " + kPieceParentsArray + ": a point made by bisection is not the " +
                "midpoint of the edge named as its parent";
    for (int e = 0; e < 2; ++e) {
      const double *p = pq + e * dim;
      const std::size_t h = std::size_t(home_rank(p, dim, d.size));
      ask[h].insert(ask[h].end(), p, p + dim);
      asked[h].push_back(v);
    }
  }
  const std::vector<std::vector<double>> known = all_to_all(reg, d.comm.get());
  reg.clear();
  const std::vector<std::vector<double>> queries = all_to_all(ask, d.comm.get());
  ask.clear();
  // At home: the points of all pieces and their levels; each query answered
  // with its point's level, or -1 when no piece has the point.
  std::vector<double> coords, levels;
  PointIndex index(coords, dim);
  for (const std::vector<double> &from : known)
    for (std::size_t at = 0; at + std::size_t(dim) < from.size(); at += std::size_t(dim) + 1) {
      const VertexId v = VertexId(levels.size());
      coords.insert(coords.end(), from.begin() + std::ptrdiff_t(at),
                    from.begin() + std::ptrdiff_t(at) + dim);
      if (index.add(v) != v) {
        coords.resize(coords.size() - std::size_t(dim));
        continue;
      }
      levels.push_back(from[at + std::size_t(dim)]);
    }
  std::vector<std::vector<double>> replies(np);
  for (std::size_t r = 0; r < np; ++r)
    for (std::size_t at = 0; at + std::size_t(dim) <= queries[r].size(); at += std::size_t(dim)) {
      const VertexId v = index.find(queries[r].data() + at);
      replies[r].push_back(v == kNoVertex ? -1.0 : levels[v]);
    }
  const std::vector<std::vector<double>> answers = all_to_all(replies, d.comm.get());
  for (std::size_t h = 0; h < np && failure.empty(); ++h)
    for (std::size_t i = 0; i < answers[h].size(); ++i) {
      const std::size_t v = asked[h][i];
      if (answers[h][i] < 0) {
        failure = path + ": " + kPieceParentsArray +
                  ": an end of a point's parent edge is a point of no piece";
        break;
      }
      if (answers[h][i] > m.level[v]) {
        failure = path + ": " + kPieceLevelArray +
                  ": a point is the midpoint of an edge with an end of a higher level";
        break;
      }
    }
  throw_first(failure, ErrorKind::Input, d);
}

// Validates where the pieces meet, as an input file is validated
// (prepare_input, then the state's consistency): each piece was validated
// alone, so what is left is what involves cells of two pieces. Every cell
// carries its piece (the array `piece`); the cells of other parts that share
// a vertex with this part come over, so every vertex of the part has its
// whole star here; the vertices whose star holds cells of two pieces are
// the pieces' border, and their stars (every facet, face and star that two
// pieces share is in one) are validated together. A facet in three cells, a
// hanging node or a state that disagrees across a facet where pieces meet is
// refused as within one piece. Throws InputError naming `path` on every
// rank.
void validate_where_pieces_meet(const DistributedMesh &d, const std::vector<double> &piece,
                                const std::string &path) {
  const Mesh &m = d.local;
  const int n = m.cell_size(), dim = m.dim;
  const std::vector<std::size_t> slot_of = neighbour_slots(d);
  std::vector<std::vector<double>> out(d.neighbours.size());
  std::vector<int> to;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    to.clear();
    for (int i = 0; i < n; ++i)
      for (int r : d.sharers[m.cell(CellId(c))[i]])
        to.push_back(r);
    if (to.empty())
      continue;
    std::sort(to.begin(), to.end());
    to.erase(std::unique(to.begin(), to.end()), to.end());
    for (int r : to) {
      std::vector<double> &o = out[slot_of[std::size_t(r)]];
      o.push_back(double(std::uint8_t(m.stage[c])));
      o.push_back(double(m.tag[c]));
      o.push_back(piece[c]);
      for (int i = 0; i < n; ++i)
        o.insert(o.end(), m.point(m.cell(CellId(c))[i]), m.point(m.cell(CellId(c))[i]) + dim);
    }
  }
  const std::vector<std::vector<double>> in = trade(d, out);
  out.clear();
  std::string failure;
  ErrorKind kind = ErrorKind::Input;
  std::size_t checked = 0;
  keep_failure(failure, kind, [&] {
    // The part and the cells around it: ids, state and piece per cell.
    std::vector<double> coords = m.coords;
    std::vector<VertexId> cells = m.cells;
    std::vector<Stage> stage = m.stage;
    std::vector<std::uint8_t> tag = m.tag;
    std::vector<double> from = piece;
    PointIndex index(coords, dim);
    for (std::size_t v = 0; v < m.num_vertices(); ++v)
      index.add(VertexId(v));
    const std::size_t record = 3 + std::size_t(n * dim);
    for (const std::vector<double> &got : in)
      for (std::size_t at = 0; at + record <= got.size(); at += record) {
        stage.push_back(Stage(std::uint8_t(got[at])));
        tag.push_back(std::uint8_t(got[at + 1]));
        from.push_back(got[at + 2]);
        for (int i = 0; i < n; ++i) {
          const double *p = got.data() + at + 3 + std::size_t(i * dim);
          VertexId v = index.find(p);
          if (v == kNoVertex) {
            v = VertexId(coords.size() / std::size_t(dim));
            coords.insert(coords.end(), p, p + dim);
            index.add(v);
          }
          cells.push_back(v);
        }
      }
    // The border of the pieces among the part's vertices.
    const std::size_t nv = coords.size() / std::size_t(dim), nc = from.size();
    std::vector<double> lo(nv, std::numeric_limits<double>::infinity()),
        hi(nv, -std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < nc; ++c)
      for (int i = 0; i < n; ++i) {
        const VertexId v = cells[c * std::size_t(n) + std::size_t(i)];
        lo[v] = std::min(lo[v], from[c]);
        hi[v] = std::max(hi[v], from[c]);
      }
    auto border = [&](VertexId v) { return v < m.num_vertices() && lo[v] != hi[v]; };
    // Their stars, as one mesh.
    Mesh b;
    b.dim = dim;
    b.marking = m.marking;
    std::vector<VertexId> id(nv, kNoVertex);
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = cells.data() + c * std::size_t(n);
      if (std::none_of(x, x + n, border))
        continue;
      for (int i = 0; i < n; ++i) {
        if (id[x[i]] == kNoVertex) {
          id[x[i]] = VertexId(b.num_vertices());
          b.coords.insert(b.coords.end(), coords.begin() + std::ptrdiff_t(x[i] * std::size_t(dim)),
                          coords.begin() + std::ptrdiff_t((x[i] + 1) * std::size_t(dim)));
        }
        b.cells.push_back(id[x[i]]);
      }
      b.stage.push_back(stage[c]);
      b.tag.push_back(tag[c]);
    }
    checked = b.num_cells();
    if (checked == 0)
      return;
    encode_state(b);
    prepare_input(b, path);
    decode_state(b, path);
  });
  if (!failure.empty())
    failure += " (where the pieces meet: in rank " + std::to_string(d.rank) + "'s " +
               std::to_string(checked) + " cells around them)";
  throw_first(failure, kind, d);
}

} // namespace

bool pvtu_has_global_ids(const std::string &path) {
  const std::vector<std::string> names = pvtu_point_arrays(path);
  return std::find(names.begin(), names.end(), kGlobalIdArray) != names.end();
}

DistributedMesh read_pvtu_parts(const std::string &path, MPI_Comm comm,
                                const PartsReadOptions &options) {
  DistributedMesh d = on_communicator(comm);
  MPI_Comm dup = d.comm.get();
  std::string failure;
  ErrorKind kind = ErrorKind::Input;
  PiecePart pp;
  bool loaded = false;
  keep_failure(failure, kind, [&] {
    const std::vector<std::string> sources = pvtu_pieces(path);
    const std::size_t k = sources.size(), P = std::size_t(d.size), r = std::size_t(d.rank);
    const std::size_t first = k * r / P, last = k * (r + 1) / P;
    load_pieces(d, pp, path, sources, first, last, options.progress);
    loaded = last > first;
  });
  throw_first(failure, kind, d);
  agree_layout(d, pp, loaded, path);
  keep_failure(failure, kind, [&] { order_part(d, pp, path); });
  throw_first(failure, kind, d);
  const bool tree = pp.tree;
  // Each cell's piece travels with it, for the validation where pieces meet.
  constexpr const char *kPieceArray = "bisect:read_piece";
  d.local.cell_data.push_back({kPieceArray, 1, std::move(pp.piece), ValueType::Int32});
  pp = {};
  Mesh &m = d.local;
  if (tree)
    check_piece_tree(d, path);
  // bisect:origin: the index of each cell in read_pvtu's order (pieces in
  // order, each rank's pieces one stretch of them).
  if (options.origin) {
    std::uint64_t count = m.num_cells(), before = 0;
    MPI_Exscan(&count, &before, 1, MPI_UINT64_T, MPI_SUM, dup);
    if (d.rank == 0)
      before = 0;
    std::erase_if(m.cell_data, [](const DataArray &a) { return a.name == kOriginArray; });
    DataArray origin{kOriginArray, 1, std::vector<double>(m.num_cells()), ValueType::Int32};
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      origin.values[c] = double(before + c);
    m.cell_data.push_back(std::move(origin));
  }
  const std::size_t cells = sum_ranks(m.num_cells(), dup);
  if (cells < std::size_t(d.size))
    throw UsageError(path + ": " + std::to_string(cells) + " cells, fewer than the " +
                     std::to_string(d.size) + " ranks");
  migrate(d, hilbert_destinations(d), tree); // (agree_layout made `tree` one)
  // The global ids: 0..N-1, each once (gather() places input vertices at
  // their ids). Each id is counted by the lowest rank holding its point.
  std::uint64_t figures[2] = {0, 0}, top = 0;
  for (std::size_t v = 0; v < d.input_vertex.size(); ++v) {
    top = std::max(top, d.input_vertex[v] + 1);
    if (d.sharers[v].empty() || d.sharers[v].front() > d.rank) {
      ++figures[0];
      figures[1] += d.input_vertex[v];
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, figures, 2, MPI_UINT64_T, MPI_SUM, dup);
  MPI_Allreduce(MPI_IN_PLACE, &top, 1, MPI_UINT64_T, MPI_MAX, dup);
  const unsigned __int128 expect = (unsigned __int128)top * (top - (top > 0)) / 2;
  if (figures[0] != top || figures[1] != std::uint64_t(expect))
    throw InputError(path, std::string("the pieces' ") + kGlobalIdArray + " are not the ids 0.." +
                               std::to_string(top ? top - 1 : 0) + " once each (their points: " +
                               std::to_string(figures[0]) + "); read the .pvtu without mpirun");
  std::optional<DataArray> pieces = take_array(m.cell_data, kPieceArray);
  validate_where_pieces_meet(d, pieces->values, path);
  return d;
}

Invariants whole_invariants(const DistributedMesh &d) {
  const Invariants part = measure_invariants(d.local, false);
  double figures[2] = {part.volume, part.boundary_measure - border_measure(d)};
  MPI_Allreduce(MPI_IN_PLACE, figures, 2, MPI_DOUBLE, MPI_SUM, d.comm.get());
  Invariants whole;
  whole.volume = figures[0];
  whole.boundary_measure = figures[1];
  return whole;
}

// ---------------------------------------------------------------- select

std::vector<CellId> select_cells(const DistributedMesh &d, const Region &region) {
  std::vector<CellId> touched = select_touching(d.local, region);
  if (!region.filter_ranks_cells()) {
    region.filter(d.local, touched);
    return touched;
  }
  // Ranked over all parts: the round(fraction N) cells (at least one) of the
  // N touched with the largest score, ties by their coordinates (Region).
  MPI_Comm comm = d.comm.get();
  const std::uint64_t mine = touched.size();
  std::uint64_t total = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (total == 0)
    return touched;
  const std::uint64_t keep = std::clamp<std::uint64_t>(
      std::uint64_t(std::llround(region.rank_fraction() * double(total))), 1, total);
  if (keep == total)
    return touched;
  std::vector<double> score(touched.size());
  for (std::size_t j = 0; j < touched.size(); ++j)
    score[j] = region.rank_score(d.local, touched[j]);
  // Every rank's scores, to find the keep-th largest (8 bytes per touched
  // cell on every rank).
  std::vector<int> counts(std::size_t(d.size)), offsets(std::size_t(d.size) + 1, 0);
  const int n = int(touched.size());
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 0; r < d.size; ++r)
    offsets[std::size_t(r) + 1] = offsets[std::size_t(r)] + counts[std::size_t(r)];
  std::vector<double> all(std::size_t(offsets.back()));
  MPI_Allgatherv(score.data(), n, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE,
                 comm);
  std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(keep - 1), all.end(),
                   std::greater<double>());
  const double threshold = all[keep - 1];
  const std::uint64_t above =
      std::uint64_t(std::count_if(all.begin(), all.end(), [&](double x) { return x > threshold; }));
  std::vector<CellId> kept;
  std::vector<CellId> tied;
  for (std::size_t j = 0; j < touched.size(); ++j) {
    if (score[j] > threshold)
      kept.push_back(touched[j]);
    else if (score[j] == threshold)
      tied.push_back(touched[j]);
  }
  // Of the cells tied at the threshold, the first keep - above by their
  // sorted coordinates: every rank's tied cells, as coordinate lists.
  const int k = d.local.dim * (d.local.dim + 1);
  std::vector<double> keys;
  for (CellId c : tied) {
    const std::array<double, 20> key = sorted_cell_coordinates(d.local, c);
    keys.insert(keys.end(), key.begin(), key.begin() + k);
  }
  const int nk = int(keys.size());
  MPI_Allgather(&nk, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 0; r < d.size; ++r)
    offsets[std::size_t(r) + 1] = offsets[std::size_t(r)] + counts[std::size_t(r)];
  std::vector<double> all_keys(std::size_t(offsets.back()));
  MPI_Allgatherv(keys.data(), nk, MPI_DOUBLE, all_keys.data(), counts.data(), offsets.data(),
                 MPI_DOUBLE, comm);
  const std::size_t ties = all_keys.size() / std::size_t(k), wanted = keep - above;
  std::vector<std::size_t> order(ties);
  std::iota(order.begin(), order.end(), std::size_t(0));
  auto key_less = [&](const double *x, const double *y) {
    return std::lexicographical_compare(x, x + k, y, y + k);
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return key_less(&all_keys[a * std::size_t(k)], &all_keys[b * std::size_t(k)]);
  });
  if (wanted > 0 && wanted <= ties) {
    const double *last = &all_keys[order[wanted - 1] * std::size_t(k)];
    for (std::size_t j = 0; j < tied.size(); ++j)
      if (!key_less(last, &keys[j * std::size_t(k)])) // key <= the last one kept
        kept.push_back(tied[j]);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

// ---------------------------------------------------------------- coarsen

namespace {

// values[v] for the vertices other parts share, raised to the largest any
// part holding the vertex has (the vertices known by their coordinates).
// Collective.
void max_over_sharers(const DistributedMesh &d, std::vector<double> &values) {
  const Mesh &m = d.local;
  const int dim = m.dim;
  const std::vector<std::size_t> slot_of = neighbour_slots(d);
  std::vector<std::vector<double>> out(d.neighbours.size());
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    for (int r : d.sharers[v]) {
      std::vector<double> &o = out[slot_of[std::size_t(r)]];
      o.insert(o.end(), m.point(VertexId(v)), m.point(VertexId(v)) + dim);
      o.push_back(values[v]);
    }
  const std::vector<std::vector<double>> in = trade(d, out);
  PointIndex index(m.coords, dim);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (!d.sharers[v].empty())
      index.add(VertexId(v));
  for (const std::vector<double> &from : in)
    for (std::size_t at = 0; at + std::size_t(dim) < from.size(); at += std::size_t(dim) + 1) {
      const VertexId v = index.find(from.data() + at);
      if (v != kNoVertex)
        values[v] = std::max(values[v], from[at + std::size_t(dim)]);
    }
}

// After vertices of the part went (removed[v], per vertex before): the
// per-vertex fields of `d` beside the mesh, compacted as the mesh was.
void drop_vertices(DistributedMesh &d, const std::vector<char> &removed,
                   std::vector<char> &eligible) {
  const std::size_t pw = 2 * std::size_t(d.local.dim);
  std::size_t w = 0, wi = 0, wp = 0;
  const std::size_t inputs = d.input_vertex.size(), known = d.parent_points.size() / pw;
  for (std::size_t v = 0; v < removed.size(); ++v) {
    if (removed[v])
      continue;
    if (w != v) // (a vector moved onto itself may come out empty)
      d.sharers[w] = std::move(d.sharers[v]);
    eligible[w] = eligible[v];
    if (v < inputs)
      d.input_vertex[wi++] = d.input_vertex[v];
    if (v < known) {
      std::copy_n(d.parent_points.begin() + std::ptrdiff_t(v * pw), pw,
                  d.parent_points.begin() + std::ptrdiff_t(wp * pw));
      ++wp;
    }
    ++w;
  }
  d.sharers.resize(w);
  eligible.resize(w);
  d.input_vertex.resize(wi);
  d.parent_points.resize(wp * pw);
}

// The input ids of the parts' vertices made 0..N-1 again, in their order,
// after coarsening removed some (gather() and write_pvtu() want them dense).
// Each id has a home rank (ranges of ids, in rank order) that counts the
// distinct ids it hears of; a prefix sum over the homes numbers them.
// Collective.
void compact_input_ids(DistributedMesh &d) {
  MPI_Comm comm = d.comm.get();
  std::uint64_t top = 0;
  for (std::uint64_t id : d.input_vertex)
    top = std::max(top, id + 1);
  MPI_Allreduce(MPI_IN_PLACE, &top, 1, MPI_UINT64_T, MPI_MAX, comm);
  const std::size_t np = std::size_t(d.size);
  auto home = [&](std::uint64_t id) {
    return std::size_t((unsigned __int128)id * np / std::max<std::uint64_t>(top, 1));
  };
  std::vector<std::vector<double>> ask(np);
  for (std::uint64_t id : d.input_vertex)
    ask[home(id)].push_back(double(id));
  const std::vector<std::vector<double>> heard = all_to_all(ask, comm);
  std::vector<double> ids;
  for (const std::vector<double> &h : heard)
    ids.insert(ids.end(), h.begin(), h.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::uint64_t count = ids.size(), before = 0;
  MPI_Exscan(&count, &before, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (d.rank == 0)
    before = 0;
  std::vector<std::vector<double>> reply(np);
  for (std::size_t r = 0; r < np; ++r)
    for (double id : heard[r])
      reply[r].push_back(double(before) +
                         double(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin()));
  const std::vector<std::vector<double>> answers = all_to_all(reply, comm);
  std::vector<std::size_t> at(np, 0);
  for (std::uint64_t &id : d.input_vertex) {
    const std::size_t h = home(id);
    id = std::uint64_t(answers[h][at[h]++]);
  }
}

} // namespace

CoarsenResult coarsen(DistributedMesh &d, const std::vector<char> &marks_in,
                      const CoarsenOptions &options,
                      const std::function<void(const CoarsenPass &)> &on_pass) {
  MPI_Comm comm = d.comm.get();
  std::string failure;
  if (marks_in.size() != d.local.num_cells())
    failure = "coarsen: " + std::to_string(marks_in.size()) + " marks for a part of " +
              std::to_string(d.local.num_cells()) + " cells";
  else if (d.local.marking == Marking::Explicit)
    failure = "coarsen: a mesh with explicit marking (bisect:edge_rank) is coarsened without "
              "mpirun (its edge ranks do not travel between ranks)";
  if (const Failure f = first_failure(failure, d.rank, d.size, comm); f.rank < d.size)
    throw UsageError(f.message);
  CoarsenResult result;
  if (!any_rank(d.local.has_tree(), comm))
    return result;
  // The marks and the pass's eligible vertices travel with their cells and
  // vertices when parts move.
  constexpr const char *kMarks = "bisect:coarsen_marked";
  constexpr const char *kEligible = "bisect:coarsen_eligible";
  std::vector<char> marks = marks_in, eligible;
  auto move_cells = [&](const std::vector<int> &dest) {
    Mesh &m = d.local;
    m.cell_data.push_back(
        {kMarks, 1, std::vector<double>(marks.begin(), marks.end()), ValueType::Int8});
    m.point_data.push_back(
        {kEligible, 1, std::vector<double>(eligible.begin(), eligible.end()), ValueType::Int8});
    migrate(d, dest, 1);
    std::optional<DataArray> mk = take_array(m.cell_data, kMarks);
    std::optional<DataArray> el = take_array(m.point_data, kEligible);
    marks.assign(mk->values.begin(), mk->values.end());
    eligible.assign(el->values.begin(), el->values.end());
  };
  for (int p = 1; options.passes <= 0 || p <= options.passes; ++p) {
    // The pass's vertices, as the whole mesh's pass finds them: made, and
    // no vertex of their star (in any part) newer.
    {
      const Mesh &m = d.local;
      const std::size_t nv = m.num_vertices();
      const int n = m.cell_size();
      // (Every part with a tree has levels: distribute(), migrate() and
      // read_pvtu_parts give them, refine() keeps them.)
      auto level = [&](std::size_t v) { return double(m.level[v]); };
      std::vector<double> around(nv, 0.0);
      for (std::size_t c = 0; c < m.num_cells(); ++c) {
        double top = 0;
        for (int i = 0; i < n; ++i)
          top = std::max(top, level(m.cell(CellId(c))[i]));
        for (int i = 0; i < n; ++i)
          around[m.cell(CellId(c))[i]] = std::max(around[m.cell(CellId(c))[i]], top);
      }
      max_over_sharers(d, around);
      eligible.assign(nv, 0);
      for (std::size_t v = 0; v < nv; ++v)
        eligible[v] = level(v) > 0 && level(v) >= around[v];
    }
    std::uint64_t figures[2] = {0, 0}; // removed vertices, merged pairs
    int rounds = 0;
    std::uint64_t moved = 0;
    // Rounds: each part runs the pass among the vertices no other part
    // holds; then the cells around each vertex still waiting on a border
    // (eligible, shared, its cells here all marked and made by bisection)
    // move to the lowest rank holding it, and the parts run again, until no
    // cell moves. Cells only move to lower ranks, so the rounds end.
    for (;;) {
      Mesh &m = d.local;
      const std::size_t nv = m.num_vertices();
      std::vector<char> among(nv), removed;
      for (std::size_t v = 0; v < nv; ++v)
        among[v] = eligible[v] && d.sharers[v].empty();
      const CoarsenPass cp = coarsen_pass_among(m, marks, among, options, removed);
      figures[0] += cp.removed_vertices;
      figures[1] += cp.merged_pairs;
      if (cp.removed_vertices)
        drop_vertices(d, removed, eligible);
      const int n = m.cell_size();
      std::vector<char> ready(m.num_vertices(), 1);
      for (std::size_t c = 0; c < m.num_cells(); ++c)
        if (!marks[c] || m.generation[c] == 0)
          for (int i = 0; i < n; ++i)
            ready[m.cell(CellId(c))[i]] = 0;
      // Where cells go: around each waiting vertex, to the lowest rank
      // holding it; and on through the waiting vertices of those cells, so
      // that a chain of vertices waiting for each other moves in one round
      // (each vertex labelled with the lowest rank that reaches it).
      std::vector<int> dest(m.num_cells(), d.rank), owner(m.num_vertices(), d.rank);
      std::vector<VertexId> work;
      auto waiting = [&](VertexId x) { return eligible[x] && ready[x]; };
      for (std::size_t v = 0; v < m.num_vertices(); ++v)
        if (waiting(VertexId(v)) && !d.sharers[v].empty() && d.sharers[v].front() < d.rank) {
          owner[v] = d.sharers[v].front();
          work.push_back(VertexId(v));
        }
      std::size_t leaving = 0;
      if (!work.empty()) {
        std::vector<std::uint32_t> start(m.num_vertices() + 1, 0);
        for (VertexId x : m.cells)
          ++start[x + 1];
        std::partial_sum(start.begin(), start.end(), start.begin());
        std::vector<CellId> around(start.back());
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t c = 0; c < m.num_cells(); ++c)
          for (int i = 0; i < n; ++i)
            around[fill[m.cell(CellId(c))[i]]++] = CellId(c);
        while (!work.empty()) {
          const VertexId v = work.back();
          work.pop_back();
          for (std::uint32_t k = start[v]; k < start[v + 1]; ++k) {
            const CellId c = around[k];
            if (owner[v] >= dest[c])
              continue;
            leaving += dest[c] == d.rank;
            dest[c] = owner[v];
            for (int i = 0; i < n; ++i) {
              const VertexId y = m.cell(c)[i];
              if (waiting(y) && owner[v] < owner[y]) {
                owner[y] = owner[v];
                work.push_back(y);
              }
            }
          }
        }
      }
      if (!any_rank(leaving > 0, comm))
        break;
      ++rounds;
      moved += leaving;
      move_cells(dest);
    }
    MPI_Allreduce(MPI_IN_PLACE, figures, 2, MPI_UINT64_T, MPI_SUM, comm);
    count_global(d);
    CoarsenPass pass;
    pass.pass = p;
    pass.removed_vertices = figures[0];
    pass.merged_pairs = figures[1];
    pass.cells = d.global_cells;
    pass.vertices = d.global_vertices;
    pass.rounds = rounds;
    MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_UINT64_T, MPI_SUM, comm);
    pass.moved_cells = moved;
    if (on_pass && d.rank == 0)
      on_pass(pass);
    if (pass.removed_vertices == 0)
      break;
    result.passes = p;
    result.removed_vertices += pass.removed_vertices;
    result.merged_pairs += pass.merged_pairs;
    if (imbalance(d) > 1.1)
      move_cells(hilbert_destinations(d));
  }
  // The input's ids without the removed vertices; the root's copy of the
  // input's tree names the old ids (gather() takes the tree from the parts).
  compact_input_ids(d);
  d.input_parent_edge.clear();
  d.input_level.clear();
  if (imbalance(d) > 1.1) {
    eligible.assign(d.local.num_vertices(), 0);
    move_cells(hilbert_destinations(d));
  }
  return result;
}

// ---------------------------------------------------------------- .pvtu

namespace {

// The DataArray declarations of a .vtu piece's PointData, CellData and
// Points, as PDataArray lines (the piece's header is plain XML up to its
// appended data).
std::string parallel_declarations(const std::string &piece) {
  // The piece's tags, without the arrays' data: every line up to </Points>
  // that opens or closes an element of interest.
  std::ifstream in(piece, std::ios::binary);
  std::string head, line;
  while (std::getline(in, line)) {
    const std::size_t lt = line.find('<');
    if (lt == std::string::npos || line.compare(lt, 9, "<Appended") == 0)
      continue;
    head += line.substr(lt, line.find('>', lt) + 1 - lt) + "\n";
    if (line.find("</Points>") != std::string::npos)
      break;
  }
  std::string out;
  for (const char *section : {"PointData", "CellData", "Points"}) {
    const std::size_t a = head.find(std::string("<") + section);
    const std::size_t b = head.find(std::string("</") + section + ">");
    out += std::string("    <P") + section + ">\n";
    if (a != std::string::npos && b != std::string::npos) {
      const std::string body = head.substr(a, b - a);
      static const std::regex array("<DataArray([^>]*?)/?>");
      static const std::regex keep(R"((type|Name|NumberOfComponents)="[^"]*")");
      for (auto it = std::sregex_iterator(body.begin(), body.end(), array);
           it != std::sregex_iterator(); ++it) {
        const std::string attrs = (*it)[1];
        std::string kept;
        for (auto k = std::sregex_iterator(attrs.begin(), attrs.end(), keep);
             k != std::sregex_iterator(); ++k)
          kept += " " + k->str();
        out += "      <PDataArray" + kept + "/>\n";
      }
    }
    out += std::string("    </P") + section + ">\n";
  }
  return out;
}

} // namespace

void write_pvtu(const std::string &path, DistributedMesh &d, bool force,
                const WriteOptions &options) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  const std::string stem = p.stem().string();
  const auto piece_name = [&](int r) { return stem + "_" + std::to_string(r) + ".vtu"; };
  const std::string piece = (p.parent_path() / piece_name(d.rank)).string();
  std::string error;
  {
    OutputSet outputs({}, force);
    int h_piece = -1, h_pvtu = -1;
    try {
      h_piece = outputs.add(piece);
      if (d.rank == 0)
        h_pvtu = outputs.add(path);
      WriteOptions o = options;
      o.format = "vtu";
      // The tree goes as the piece arrays below; put back after writing.
      const bool tree = d.local.has_tree();
      std::vector<std::uint16_t> generation = std::move(d.local.generation),
                                 level = std::move(d.local.level);
      std::vector<VertexId> parents = std::move(d.local.parent_edge);
      d.local.clear_tree();
      // Each point's id in the mesh the run started from (-1: made since),
      // for read_pvtu (state.hpp).
      DataArray ids{kGlobalIdArray, 1, std::vector<double>(d.local.num_vertices(), -1.0),
                    ValueType::Int64};
      for (std::size_t v = 0; v < d.input_vertex.size(); ++v)
        ids.values[v] = double(d.input_vertex[v]);
      d.local.point_data.push_back(std::move(ids));
      // The tree, its parents named by coordinates (state.hpp).
      if (tree) {
        const Mesh &m = d.local;
        const std::size_t nv = m.num_vertices(), k = 2 * std::size_t(m.dim);
        DataArray gen{kPieceGenerationArray, 1,
                      std::vector<double>(generation.begin(), generation.end()), ValueType::UInt16};
        DataArray lev{kPieceLevelArray, 1, std::vector<double>(nv, 0.0), ValueType::UInt16};
        DataArray par{kPieceParentsArray, int(k), std::vector<double>(nv * k), ValueType::Float64};
        for (std::size_t v = 0; v < nv; ++v) {
          double *to = par.values.data() + v * k;
          const double *far =
              (v + 1) * k <= d.parent_points.size() ? d.parent_points.data() + v * k : nullptr;
          if (parents[2 * v] != kNoVertex) {
            std::copy_n(m.point(parents[2 * v]), m.dim, to);
            std::copy_n(m.point(parents[2 * v + 1]), m.dim, to + m.dim);
          } else if (far && !std::isnan(far[0])) {
            std::copy_n(far, k, to);
          } else {
            std::copy_n(m.point(VertexId(v)), m.dim, to);
            std::copy_n(m.point(VertexId(v)), m.dim, to + m.dim);
          }
          const bool made = !std::equal(to, to + m.dim, m.point(VertexId(v)));
          lev.values[v] = level.size() == nv ? double(level[v]) : double(made);
          if (made != (lev.values[v] != 0))
            throw CheckError("write_pvtu: rank " + std::to_string(d.rank) +
                             " lost the parents of " + "a vertex made by bisection");
        }
        d.local.cell_data.push_back(std::move(gen));
        d.local.point_data.push_back(std::move(lev));
        d.local.point_data.push_back(std::move(par));
      }
      auto drop_ids = [&] {
        auto piece_array = [](const DataArray &a) {
          return a.name == kGlobalIdArray || a.name == kPieceGenerationArray ||
                 a.name == kPieceLevelArray || a.name == kPieceParentsArray;
        };
        std::erase_if(d.local.point_data, piece_array);
        std::erase_if(d.local.cell_data, piece_array);
      };
      try {
        write_mesh_file_with_state(outputs.file(h_piece), piece, d.local, o);
        drop_ids();
      } catch (...) {
        drop_ids();
        d.local.generation = std::move(generation);
        d.local.level = std::move(level);
        d.local.parent_edge = std::move(parents);
        throw;
      }
      d.local.generation = std::move(generation);
      d.local.level = std::move(level);
      d.local.parent_edge = std::move(parents);
      if (d.rank == 0) {
        std::ostringstream x;
        x << "<?xml version=\"1.0\"?>\n"
          << "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
             "header_type=\"UInt64\">\n"
          << "  <PUnstructuredGrid GhostLevel=\"0\">\n"
          << parallel_declarations(outputs.file(h_piece));
        for (int r = 0; r < d.size; ++r)
          x << "    <Piece Source=\"" << piece_name(r) << "\"/>\n";
        x << "  </PUnstructuredGrid>\n</VTKFile>\n";
        std::ofstream f(outputs.file(h_pvtu), std::ios::binary | std::ios::trunc);
        f << x.str();
        f.flush();
        if (!f)
          throw InputError(path, "cannot write: " + write_failure(errno));
      }
    } catch (const Error &e) {
      error = e.what();
    }
    // Every rank renames only when every rank has written.
    const Failure f = first_failure(error, d.rank, d.size, d.comm.get());
    if (f.rank == d.size) {
      outputs.commit();
      MPI_Barrier(d.comm.get());
      return;
    }
    error = f.message;
  }
  throw InputError({}, error);
}

} // namespace bisect
