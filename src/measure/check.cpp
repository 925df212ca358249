// Conformity checks and input validation (ALGORITHMS.md §7).
//
// Everything topological runs on sub-simplices identified by their sorted
// vertex ids. Uniqueness is found without maps: sub-simplices are bucketed by
// their smallest vertex id with a counting sort (in memory-bounded chunks),
// then each small bucket is sorted by the remaining ids
// (see for_each_subsimplex).
//
// Geometric tests use the same kernels as measure.cpp; the hanging-node test
// hashes boundary vertices into a uniform grid and tests every boundary facet
// against the vertices in its bounding box.
#include "bisect/check.hpp"
#include "core/dimension.hpp"
#include "core/geometry.hpp"
#include "core/names.hpp"
#include "measure/check_testing.hpp"

#include "bisect/measure.hpp"
#include "bisect/text.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <numeric>
#include <stdexcept>
#include <string>
#include <sys/mman.h>
#include <type_traits>
#include <utility>
#include <vector>

namespace bisect {
namespace {

// ---- local numbering of sub-simplices ---------------------------------------

constexpr int binomial(int n, int k) {
  int r = 1;
  for (int i = 1; i <= k; ++i)
    r = r * (n - k + i) / i;
  return r;
}

// All K-subsets of {0..N-1} in lexicographic order (for K = N-1, subset m
// omits local vertex N-1-m; subsimplices() renumbers facets).
template <int N, int K> constexpr std::array<std::array<int, K>, binomial(N, K)> combinations() {
  std::array<std::array<int, K>, binomial(N, K)> out{};
  std::array<int, K> c{};
  for (int i = 0; i < K; ++i)
    c[i] = i;
  for (int m = 0; m < binomial(N, K); ++m) {
    out[m] = c;
    int i = K - 1;
    while (i >= 0 && c[i] == N - K + i)
      --i;
    if (i < 0)
      break;
    ++c[i];
    for (int j = i + 1; j < K; ++j)
      c[j] = c[j - 1] + 1;
  }
  return out;
}

// The K-vertex sub-simplices of a cell, numbered so that for facets (K = N-1)
// subset m omits local vertex m, as numbering.hpp numbers facets; other sizes
// in lexicographic order.
template <int N, int K> constexpr std::array<std::array<int, K>, binomial(N, K)> subsimplices() {
  auto out = combinations<N, K>();
  if constexpr (K == N - 1) // lexicographic subset m omits N-1-m: reverse
    for (int m = 0; m < K / 2 + 1 && m < N - 1 - m; ++m)
      std::swap(out[m], out[N - 1 - m]);
  return out;
}

template <int Dim> constexpr int opposite_of_facet(int m) {
  return m;
}

template <int K> void sort_small(std::array<VertexId, K> &a) {
  for (int i = 1; i < K; ++i)
    for (int j = i; j > 0 && a[j] < a[j - 1]; --j)
      std::swap(a[j], a[j - 1]);
}

// Sorts the N ids of a cell by a branch-free sorting network, carrying each
// id's local index along; returns the parity of the permutation (0 even,
// 1 odd): every exchange made is one transposition. Random ids made the
// branches of an insertion sort a coin toss.
template <int N>
constexpr auto kNetwork = [] {
  if constexpr (N == 3)
    return std::array<std::pair<int, int>, 3>{{{0, 1}, {1, 2}, {0, 1}}};
  else if constexpr (N == 4)
    return std::array<std::pair<int, int>, 5>{{{0, 1}, {2, 3}, {0, 2}, {1, 3}, {1, 2}}};
  else
    return std::array<std::pair<int, int>, 9>{
        {{0, 1}, {3, 4}, {2, 4}, {2, 3}, {0, 3}, {0, 2}, {1, 4}, {1, 3}, {1, 2}}};
}();

// The smallest and second smallest of a cell's N ids.
template <int N>
[[gnu::always_inline]] inline std::pair<VertexId, VertexId> two_smallest(const VertexId *cell) {
  VertexId first = std::min(cell[0], cell[1]), second = std::max(cell[0], cell[1]);
  for (int i = 2; i < N; ++i) {
    second = std::min(second, std::max(first, cell[i]));
    first = std::min(first, cell[i]);
  }
  return {first, second};
}

// keys[i] = cell's i-th smallest id << 3 | its local index.
template <int N>
[[gnu::always_inline]] inline int sort_cell(const VertexId *cell,
                                            std::array<std::uint64_t, N> &keys) {
  for (int i = 0; i < N; ++i)
    keys[i] = std::uint64_t(cell[i]) << 3 | unsigned(i);
  int parity = 0;
  for (const auto &[a, b] : kNetwork<N>) {
    const std::uint64_t x = keys[a], y = keys[b];
    parity ^= int(y < x);
    keys[a] = std::min(x, y);
    keys[b] = std::max(x, y);
  }
  return parity;
}

constexpr std::size_t kChunkBytes = std::size_t(96) << 20;

// See check_testing.hpp.
bool g_sorted_final_walk = false;
bool g_wide_final_walk = false;
bool g_own_overlap_search = false;
bool g_overlap_fast_path = true;        // centroids_wound_once before find_overlap
bool g_overlap_fast_path_taken = false; // what its last call decided
// The faces the angle check skipped, when a test asks (see check_testing.hpp).
std::vector<std::vector<VertexId>> *g_skipped_faces = nullptr;
std::mutex g_skipped_faces_mutex;
// The hashing path's piece size (see match_bucket); a test sets it small.
constexpr std::size_t kMatchPiece = 2048;
std::size_t g_match_piece = kMatchPiece;
// A walk's buffer budget set by a test (0: the walks' own).
std::size_t g_chunk_bytes = 0;
// Whether facet_pass takes the narrow walk where it fits (a test turns it off).
bool g_narrow_facet_walk = true;
// Whether the 4D angle check walks all triangles (a test turns it on) instead
// of finding them from the vertex stars.
bool g_walk_fold4 = false;

// An allocator whose resize() leaves new elements uninitialised (for trivial
// types): the walk's buffer is written in full before it is read, and
// zero-filling ~100 MB per walk was a tenth of `bisect info`'s time. Large
// blocks are mapped on transparent huge pages where the kernel allows them
// (MADV_HUGEPAGE), their pages populated at once by all threads, a piece
// each (MADV_POPULATE_WRITE). On the virtual machines this project runs on,
// the first touch of each 4 KiB page costs a trip to the hypervisor even
// after populating: touching 256 MB populated in 4 KiB pages took 0.32 s,
// in 2 MiB pages 0.01 s. With huge pages `bisect info` of a 5.4M-tet file
// took 2.46-2.56 s instead of 2.59-3.08 (26k page faults instead of 71k), of
// a 5.2M-pentatope one 6.0-6.2 s instead of 6.5-7.0. (An earlier trial on
// another machine saw the kernel compact memory first, and a 144 MB
// buffer's first scan take 0.2-0.3 s instead of 0.05.)
template <class T> struct UninitialisedAllocator : std::allocator<T> {
  template <class U> struct rebind { using other = UninitialisedAllocator<U>; };
  UninitialisedAllocator() = default;
  template <class U> UninitialisedAllocator(const UninitialisedAllocator<U> &) noexcept {}
  static constexpr std::size_t kLarge = std::size_t(8) << 20;
  static std::size_t mapped_bytes(std::size_t n) {
    constexpr std::size_t kPage = 4096;
    return (n * sizeof(T) + kPage - 1) / kPage * kPage;
  }
  T *allocate(std::size_t n) {
    if (n * sizeof(T) < kLarge)
      return std::allocator<T>::allocate(n);
    const std::size_t len = mapped_bytes(n);
    const int workers = int(std::clamp<std::size_t>(len / kLarge, 1, std::size_t(threads())));
    void *p = mmap(nullptr, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED)
      throw std::bad_alloc();
    madvise(p, len, MADV_HUGEPAGE); // a hint: nothing changes where the kernel refuses
    // The kernel clears the pages in the thread that asks; page by page
    // where it has no MADV_POPULATE_WRITE (before Linux 5.14).
    constexpr int kPopulateWrite = 23; // MADV_POPULATE_WRITE
    constexpr std::size_t kPiece = std::size_t(2) << 20;
    const std::size_t pieces = (len + kPiece - 1) / kPiece;
    char *const base = static_cast<char *>(p);
#pragma omp parallel for num_threads(workers) schedule(static)
    for (std::size_t k = 0; k < pieces; ++k) {
      const std::size_t size = std::min(kPiece, len - k * kPiece);
      if (madvise(base + k * kPiece, size, kPopulateWrite) != 0)
        for (std::size_t at = 0; at < size; at += 4096)
          static_cast<volatile char *>(base)[k * kPiece + at] = 0;
    }
    return static_cast<T *>(p);
  }
  void deallocate(T *p, std::size_t n) {
    if (n * sizeof(T) < kLarge)
      return std::allocator<T>::deallocate(p, n);
    munmap(p, mapped_bytes(n));
  }
  template <class U> void construct(U *p) noexcept {
    ::new (static_cast<void *>(p)) U;
  }
  template <class U, class... Args> void construct(U *p, Args &&...args) {
    ::new (static_cast<void *>(p)) U(std::forward<Args>(args)...);
  }
};

constexpr std::uint32_t kSideBit = std::uint32_t(1) << 31;

template <int Dim> int facet_side(const VertexId *cell, int m, int cell_sign);

template <int Bits>
using UIntFor =
    std::conditional_t<Bits <= 32, std::uint32_t,
                       std::conditional_t<Bits <= 64, std::uint64_t, unsigned __int128>>;

// A hash table's slots for the entries a few places ahead, found and
// prefetched early: a probe then rarely waits for the core's second-level
// cache. slot_of(i) is entry i's first slot.
template <class SlotOf> class SlotsAhead {
public:
  template <class Slot>
  SlotsAhead(const Slot *slots, std::size_t n, SlotOf slot_of) : n_(n), slot_of_(slot_of) {
    for (std::size_t i = 0; i < std::min(n, kAhead); ++i) {
      ring_[i] = slot_of_(i);
      __builtin_prefetch(&slots[ring_[i]], 1);
    }
  }
  // Entry i's first slot (i = 0, 1, ... in turn); asks for entry i + kAhead's.
  template <class Slot> std::size_t operator()(const Slot *slots, std::size_t i) {
    const std::size_t at = ring_[i % kAhead];
    if (i + kAhead < n_) {
      const std::size_t next = slot_of_(i + kAhead);
      ring_[i % kAhead] = next;
      __builtin_prefetch(&slots[next], 1);
    }
    return at;
  }

private:
  static constexpr std::size_t kAhead = 8;
  std::size_t ring_[kAhead];
  std::size_t n_;
  SlotOf slot_of_;
};

// The walk in pieces. The sub-simplices are grouped by their smallest id v
// in two levels: coarse buckets of 2^shift consecutive ids, then, one coarse
// bucket at a time and within the cache, fine buckets of one id each. There
// are at least kStreams coarse buckets, more when that leaves more than
// about kBucketEntries sub-simplices in one: a chunk appends to its coarse
// buckets all at once, which stays in the cache while a chunk holds no more
// than a few thousand of them, and a coarse bucket is visited within the
// core's cache only while it is small (with the count fixed at 1024, a
// 26 M-tet mesh put 180,000 facets in each, and the final check spent twice
// as long per facet as on a 3 M-tet one). A single scatter into one bucket
// per vertex put each write at a random place in a buffer far larger than
// the cache, and a cache miss per sub-simplex was most of the final check's
// time.
//
// The constructor counts the coarse buckets; chunk [b0, b1) of coarse
// buckets fills `buffer` from one scan of the cells and visits its
// sub-simplices in key order. Chunks are independent: several threads could
// walk different chunks, each with its own buffer and visitor.
//
// FineInKey (the final check's facets, SideOnly): each entry's place in its
// coarse bucket goes into the packed integer's top bits instead of a 2-byte
// array beside it, when the ids are narrow enough to leave room (see
// final_facet_pass): 8 bytes an entry instead of 10, and one stream per
// coarse bucket in the scan instead of two.
//
// CellRefs (facets with references, narrow ids): the packed integer holds
// the cell and the side bit instead of the 32-bit reference, in the bits the
// narrow ids leave free of 64, so that a facet takes 8 bytes instead of 16;
// the visitor gets cell * M | side bit (no facet number: FacetVisitor finds
// the one vertex it needs, of boundary facets, from the cell). On a 5.4M-tet
// mesh (969k vertices: 20-bit ids, 23-bit cells) validation's facet pass
// took 0.64-0.65 s instead of 0.77-0.97 (2 threads).
template <int Dim, int K, bool WithRefs, bool SideOnly, int IdBits = SideOnly ? 31 : 32,
          bool FineInKey = false, bool CellRefs = false>
struct Walk {
  static_assert(K >= 2 && K <= 4);
  static constexpr auto subsets = subsimplices<Dim + 1, K>();
  static constexpr int M = int(subsets.size());
  static_assert(!SideOnly || (WithRefs && K == Dim));
  static_assert(!CellRefs || (K == Dim && WithRefs && !SideOnly && IdBits < 32));
  static constexpr int kRefBits = SideOnly   ? 1
                                  : CellRefs ? 64 - IdBits * (K - 1)
                                  : WithRefs ? 32
                                             : 0;
  static constexpr int kIdBits = IdBits;
  static_assert(IdBits == 32 || SideOnly || CellRefs);
  static constexpr std::size_t kStreams = 1024;
  static constexpr std::size_t kBucketEntries = 16384;
  static constexpr std::size_t kBlock = 16;               // coarse buckets per visitor (see chunk)
  static constexpr std::size_t kCellsPerThread = 1 << 16; // fewer cells: fewer threads
  static_assert(!FineInKey || SideOnly);
  // FineInKey: where an entry's place in its coarse bucket starts.
  static constexpr int kFineShift = kIdBits * (K - 1) + kRefBits;
  using Packed = UIntFor<FineInKey ? 64 : kIdBits *(K - 1) + kRefBits>;
  using Buffer = std::vector<Packed, UninitialisedAllocator<Packed>>;
  using Fine = std::vector<std::uint16_t, UninitialisedAllocator<std::uint16_t>>;
  // A chunk's entries and each entry's smallest id within its coarse bucket,
  // sized once for the largest chunk: growing them chunk by chunk copied the
  // old entries and touched fresh pages again.
  struct Buffers {
    Buffer packed;
    Fine fine;
    // Facet walks over several chunks: per cell, the chunks of its smallest
    // and second smallest ids (the only chunks its facets go to), found by
    // the first chunk's scan; later scans read these 2 bytes instead of the
    // cell's ids. Each chunk rescanned all cells, and on a 26 M-tet mesh
    // (11 chunks) that was a sixth of the final check. Empty: not used.
    std::vector<std::uint8_t, UninitialisedAllocator<std::uint8_t>> pairs;
    std::vector<std::uint8_t> chunk_of; // per coarse bucket
  };

  const Mesh &mesh;
  const std::vector<std::int8_t> *signs;
  int shift = 0;                  // a coarse bucket holds 2^shift consecutive smallest ids
  std::vector<std::size_t> start; // start[b] .. start[b+1]: coarse bucket b

  static VertexId min_of(const VertexId *cell, int m) {
    VertexId v = cell[subsets[m][0]];
    for (int i = 1; i < K; ++i)
      v = std::min(v, cell[subsets[m][i]]);
    return v;
  }

  // The cells are scanned by `parts` threads, part t the cells
  // [part_begin(t), part_begin(t + 1)); counts[t * coarse + b] is the number
  // of sub-simplices part t puts in coarse bucket b. Where an entry lands
  // within its bucket depends on the parts, but each fine bucket is sorted
  // in full (the packed integer is the whole key), so nothing visited does.
  int parts = 1;
  std::vector<std::size_t> counts;

  std::size_t part_begin(int t) const { return mesh.num_cells() * std::size_t(t) / parts; }

  // The coarse buckets' width: 2^shift ids.
  static int shift_for(std::size_t nv, std::size_t nc) {
    const std::size_t buckets = std::max(kStreams, nc * std::size_t(M) / kBucketEntries);
    int shift = 0;
    while (shift < 16 && (nv >> shift) > buckets)
      ++shift;
    return shift;
  }

  // Whether the mesh's ids fit this walk's packing (FineInKey: with room
  // for the place in the coarse bucket above them).
  static bool fits(std::size_t nv, std::size_t nc) {
    if (nv >= (std::size_t(1) << kIdBits))
      return false;
    if constexpr (CellRefs)
      if (nc >= (std::size_t(1) << (kRefBits - 1)))
        return false;
    return !FineInKey || kFineShift + shift_for(nv, nc) <= 63; // bit 63: match_packed
  }

  Walk(const Mesh &mesh_, const std::vector<std::int8_t> *signs_) : mesh(mesh_), signs(signs_) {
    const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
    if (nc * M >= std::size_t(kSideBit))
      throw ResourceError("", "mesh too large for the 32-bit sub-simplex references of the checks");
    if (SideOnly && !fits(nv, nc))
      throw ResourceError("", "mesh too large for the vertex ids of the final check");
    if (CellRefs && !fits(nv, nc))
      throw ResourceError("", "internal: a narrow facet walk on a mesh too large for it");
    shift = shift_for(nv, nc);
    const std::size_t coarse = nv ? ((nv - 1) >> shift) + 1 : 0;
    parts = int(std::clamp<std::size_t>(nc / kCellsPerThread, 1, std::size_t(threads())));
    counts.assign(std::size_t(parts) * coarse, 0);
#pragma omp parallel for num_threads(parts) schedule(static, 1)
    for (int t = 0; t < parts; ++t) {
      std::size_t *mine = counts.data() + std::size_t(t) * coarse;
      for (std::size_t c = part_begin(t), end = part_begin(t + 1); c < end; ++c) {
        const VertexId *cell = mesh.cell(CellId(c));
        if constexpr (K == Dim) {
          // A facet's smallest id is the cell's smallest, except for the
          // facet without it, whose smallest is the cell's second smallest.
          const auto [first, second] = two_smallest<Dim + 1>(cell);
          mine[first >> shift] += Dim;
          ++mine[second >> shift];
        } else {
          for (int m = 0; m < M; ++m)
            ++mine[min_of(cell, m) >> shift];
        }
      }
    }
    start.assign(coarse + 1, 0);
    for (int t = 0; t < parts; ++t)
      for (std::size_t b = 0; b < coarse; ++b)
        start[b + 1] += counts[std::size_t(t) * coarse + b];
    for (std::size_t b = 1; b <= coarse; ++b)
      start[b] += start[b - 1];
  }

  // The chunks [b0, b1) of coarse buckets of at most `cap` entries each (at
  // least one bucket).
  std::vector<std::pair<std::size_t, std::size_t>> chunks(std::size_t cap) const {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    const std::size_t coarse = start.size() - 1;
    for (std::size_t b0 = 0; b0 < coarse;) {
      std::size_t b1 = b0 + 1;
      while (b1 < coarse && start[b1 + 1] - start[b0] <= cap)
        ++b1;
      out.emplace_back(b0, b1);
      b0 = b1;
    }
    return out;
  }

  // How many entries a buffer budget of `bytes` holds (a test's budget,
  // when set, instead).
  static std::size_t entries_in(std::size_t bytes) {
    return std::max<std::size_t>((g_chunk_bytes ? g_chunk_bytes : bytes) /
                                     (sizeof(Packed) + (FineInKey ? 0 : sizeof(std::uint16_t))),
                                 1);
  }

  // The buffers for the largest of `chunks`.
  Buffers buffers_for(const std::vector<std::pair<std::size_t, std::size_t>> &chunks) const {
    std::size_t most = 0;
    for (const auto &[b0, b1] : chunks)
      most = std::max(most, start[b1] - start[b0]);
    Buffers buffers;
    buffers.packed.reserve(most);
    if (shift && !FineInKey)
      buffers.fine.reserve(most);
    if (K == Dim && WithRefs && chunks.size() > 1 && chunks.size() < 256) {
      buffers.pairs.resize(2 * mesh.num_cells());
      buffers.chunk_of.resize(start.size() - 1);
      for (std::size_t i = 0; i < chunks.size(); ++i)
        std::fill(buffers.chunk_of.begin() + std::ptrdiff_t(chunks[i].first),
                  buffers.chunk_of.begin() + std::ptrdiff_t(chunks[i].second), std::uint8_t(i));
    }
    return buffers;
  }

  // One sub-simplex, packed: the K-1 ids after the smallest, then the
  // reference (or the side bit), high to low bits.
  Packed pack(const VertexId *cell, std::size_t c, int m, std::array<VertexId, K> &key) const {
    for (int i = 0; i < K; ++i)
      key[i] = cell[subsets[m][i]];
    sort_small<K>(key);
    unsigned __int128 p = 0;
    for (int j = 1; j < K; ++j)
      p = (p << kIdBits) | key[j];
    if constexpr (SideOnly) {
      p = (p << 1) | unsigned(signs && facet_side<Dim>(cell, m, (*signs)[c]) > 0);
    } else if constexpr (CellRefs) {
      p = (p << kRefBits) | (unsigned __int128)(c << 1) |
          unsigned(signs && facet_side<Dim>(cell, m, (*signs)[c]) > 0);
    } else if constexpr (WithRefs) {
      std::uint32_t ref = std::uint32_t(c * M + m);
      if constexpr (K == Dim)
        if (signs && facet_side<Dim>(cell, m, (*signs)[c]) > 0)
          ref |= kSideBit;
      p = (p << 32) | ref;
    }
    return Packed(p);
  }

  // Sorts [first, last), the sub-simplices of smallest id v, and visits them.
  template <class It, class Visit>
  static void visit_bucket(VertexId v, It first, It last, std::vector<std::uint32_t> &group,
                           Visit &visit) {
    std::sort(first, last);
    std::array<VertexId, K> key;
    key[0] = v;
    for (auto i = first; i != last;) {
      const Packed rest = *i >> kRefBits;
      group.clear();
      auto j = i;
      for (; j != last && (*j >> kRefBits) == rest; ++j)
        if constexpr (SideOnly)
          group.push_back(std::uint32_t(*j & 1u) ? kSideBit : 0u);
        else if constexpr (CellRefs)
          group.push_back(std::uint32_t(((*j >> 1) & ((Packed(1) << (kRefBits - 1)) - 1)) * M) |
                          (std::uint32_t(*j & 1u) ? kSideBit : 0u));
        else if constexpr (WithRefs)
          group.push_back(std::uint32_t(*j));
      for (int t = K - 1; t >= 1; --t)
        key[t] =
            VertexId((rest >> (kIdBits * (K - 1 - t))) & Packed(0xFFFFFFFFu >> (32 - kIdBits)));
      visit(std::as_const(key), WithRefs ? group.data() : nullptr, int(j - i));
      i = j;
    }
  }

  // The final check's fast path (SideOnly, a visitor with interior_pairs):
  // a coarse bucket's facets matched by hashing, in the cache, instead of
  // the fine scatter and sorts. A stamp per slot marks the bucket that
  // filled it, so the table is never cleared.
  // FineInKey: an entry's place in its coarse bucket.
  static std::uint16_t fine_of(Packed p) {
    if constexpr (FineInKey)
      return std::uint16_t(p >> kFineShift);
    else
      return 0;
  }

  struct MatchSlot {
    Packed ids;          // the packed facet without its side bit
    std::uint32_t stamp; // the bucket that filled the slot (0: none yet)
    std::uint16_t fine;  // the smallest id's place in the coarse bucket
    std::uint8_t side;   // the first copy's side bit
    std::uint8_t copies; // 1 or 2
  };
  struct MatchTable {
    std::vector<MatchSlot> slots;
    std::uint32_t stamp = 0;
    // A coarse bucket split by the high bits of `fine` (see match_bucket).
    std::vector<Packed> ids;
    std::vector<std::uint16_t> fine;
    std::vector<std::uint32_t> count;
    // The slots filled by a range, in the order filled.
    std::vector<std::uint32_t> filled;
    // FineInKey: 8-byte slots (see match_packed), all zero between ranges.
    std::vector<std::uint64_t> packed;
  };

  // FineInKey's table: a slot is the first copy's entry itself (0: empty;
  // a facet's key is never 0, its second id being above its first), with
  // bit 63 set once the second copy has come. Half the bytes of a MatchSlot,
  // so that a piece's table stays in the core's first-level cache; without
  // stamps, the slots a range filled are cleared after it.
  static constexpr std::uint64_t kSecondCopy = std::uint64_t(1) << 63;
  static bool match_packed(const Packed *ids, std::size_t n, MatchTable &table,
                           std::vector<std::pair<std::uint16_t, Packed>> &singles,
                           std::size_t &pairs) {
    static_assert(FineInKey && sizeof(Packed) == 8);
    constexpr std::uint64_t kKey = ~(kSecondCopy | 1u);
    // At least 4n slots, at most an eighth of them filled (most facets come
    // in pairs): fewer probes meet another key than at 2n, and a piece's
    // table (64 KiB for 2,048 entries) still stays in the core's caches.
    // 4D, 26 M entries: 0.38 s for the whole check instead of 0.40.
    std::size_t cap = 128;
    while (cap < 4 * n)
      cap *= 2;
    if (table.packed.size() < cap)
      table.packed.assign(cap, 0);
    const std::size_t mask = cap - 1;
    std::uint64_t *const slots = table.packed.data();
    if (table.filled.size() < n)
      table.filled.resize(n);
    std::uint32_t *const filled = table.filled.data();
    std::size_t fills = 0, matched = 0;
    std::uint64_t bad = 0;
    // Multiplicative hashing: the product's top bits (every key bit reaches
    // them) pick the slot.
    const int drop = 64 - std::countr_zero(cap);
    auto slot_of = [&](std::size_t i) {
      return std::size_t(((ids[i] >> 1) * 0x9E3779B97F4A7C15ull) >> drop);
    };
    // (Prefetched: 0.04 s less in 26 M entries of a 4D mesh.)
    SlotsAhead ahead(slots, n, slot_of);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t e = ids[i];
      for (std::size_t at = ahead(slots, i);; at = (at + 1) & mask) {
        const std::uint64_t s = slots[at];
        const std::uint64_t differ = (s ^ e) & kKey; // 0: the same facet
        // An empty slot or the same facet: one test of both, by their
        // minimum. (Whether a facet is the first or the second of its pair
        // is a coin toss; g++ made `empty | same` two branches, the first
        // mispredicted half the time, and likewise a conditional for the
        // slot's new value: masks instead.)
        if (std::min(s, differ) == 0) {
          const std::uint64_t empty = s == 0, same = differ == 0;
          // A third copy, or two cells on one side.
          bad |= same & ((s >> 63) | (~(s ^ e) & 1u));
          matched += same;
          const std::uint64_t first = std::uint64_t(0) - empty;
          slots[at] = (e & first) | ((s | kSecondCopy) & ~first);
          filled[fills] = std::uint32_t(at);
          fills += empty;
          break;
        }
      }
    }
    if (!bad) {
      pairs += matched;
      if (2 * matched != n) {
        const std::size_t first = singles.size();
        for (std::size_t k = 0; k < fills; ++k)
          if (const std::uint64_t s = slots[filled[k]]; !(s & kSecondCopy))
            singles.emplace_back(fine_of(s), Packed(s));
        std::sort(singles.begin() + std::ptrdiff_t(first), singles.end());
      }
    }
    for (std::size_t k = 0; k < fills; ++k)
      slots[filled[k]] = 0;
    return !bad;
  }

  // Hashes entries [0, n) of (ids, fine), entries of one coarse bucket, and
  // appends the facets seen once to `singles`, sorted. Adds the facets seen
  // twice with opposite sides to `pairs`; false on a third copy or two
  // copies on one side.
  static bool match_range(const Packed *ids, const std::uint16_t *fine, std::size_t n,
                          MatchTable &table, std::vector<std::pair<std::uint16_t, Packed>> &singles,
                          std::size_t &pairs) {
    if constexpr (FineInKey)
      return match_packed(ids, n, table, singles, pairs);
    // Most facets come in pairs, so at most n / 2 + 1 distinct keys: with
    // at least 2n slots a load of at most about a quarter, so that a probe
    // rarely meets another key and the one branch below is predictable.
    // Whether a facet is the first or the second of its pair is a coin toss;
    // it decides the slot's new contents arithmetically, not by a branch.
    std::size_t cap = 128;
    while (cap < 2 * n)
      cap *= 2;
    if (table.slots.size() < cap || table.stamp == 0xFFFFFFFFu) {
      table.slots.assign(std::max(cap, table.slots.size()), MatchSlot{0, 0, 0, 0, 0});
      table.stamp = 0;
    }
    const std::uint32_t stamp = ++table.stamp;
    // A table sized for this range: the low bits of the hash.
    const std::size_t mask = cap - 1;
    std::size_t matched = 0;
    unsigned bad = 0;
    // The slots are found a few entries ahead and prefetched (SlotsAhead).
    MatchSlot *const slots = table.slots.data();
    if (table.filled.size() < n)
      table.filled.resize(n);
    std::uint32_t *const filled = table.filled.data();
    std::size_t fills = 0;
    auto slot_of = [&](std::size_t i) {
      const Packed key = ids[i] >> 1;
      std::uint64_t h = std::uint64_t(key);
      if constexpr (!FineInKey)
        h ^= std::uint64_t(fine[i]) << 48;
      if constexpr (sizeof(Packed) > 8)
        h ^= std::uint64_t(key >> 64);
      h ^= h >> 33;
      h *= 0xFF51AFD7ED558CCDull;
      h ^= h >> 33;
      return std::size_t(h & mask);
    };
    SlotsAhead ahead(slots, n, slot_of);
    for (std::size_t i = 0; i < n; ++i) {
      const Packed key = ids[i] >> 1;
      const std::uint8_t side = std::uint8_t(ids[i] & 1u);
      const std::uint16_t f = FineInKey ? 0 : fine[i];
      for (std::size_t at = ahead(slots, i);; at = (at + 1) & mask) {
        MatchSlot &slot = slots[at];
        const unsigned empty = slot.stamp != stamp;
        const unsigned same = (slot.ids == key) & (slot.fine == f) & (empty ^ 1u);
        unsigned stop = empty | same;
        // One branch on both (see match_packed): the empty asm hides how
        // `stop` was made, or g++ tests `same` and `empty` apart again.
        asm("" : "+r"(stop));
        if (stop) {
          // A third copy, or two cells on one side.
          bad |= same & ((slot.copies != 1) | (slot.side == side));
          matched += same;
          const std::uint8_t copies = std::uint8_t(slot.copies * (empty ^ 1u) + 1);
          const std::uint8_t first_side =
              std::uint8_t((side & (0u - empty)) | (slot.side & (empty - 1u)));
          slot = MatchSlot{key, stamp, f, first_side, copies};
          filled[fills] = std::uint32_t(at);
          fills += empty;
          break;
        }
      }
    }
    if (bad)
      return false;
    pairs += matched;
    // Inside the domain every facet is matched: no need to scan the table.
    if (2 * matched == n)
      return true;
    const std::size_t first = singles.size();
    for (std::size_t k = 0; k < fills; ++k) {
      const MatchSlot &slot = slots[filled[k]];
      if (slot.copies == 1)
        singles.emplace_back(FineInKey ? fine_of(slot.ids << 1) : slot.fine,
                             Packed((slot.ids << 1) | slot.side));
    }
    std::sort(singles.begin() + std::ptrdiff_t(first), singles.end());
    return true;
  }

  // Matches the entries [lo, hi) of coarse bucket b. When every facet comes
  // once, or twice with opposite sides, visits the single ones in key order
  // (each with count 1, as the sorted walk would), tells the visitor how many
  // pairs there were, and returns true. Otherwise visits nothing and returns
  // false: the sorted walk then finds and names the first offending facet.
  // A large bucket is first split by the high bits of its entries' smallest
  // ids into pieces of about kMatchPiece entries, so that the table of each
  // stays in the core's cache: with one table per coarse bucket (1 MB for a
  // 4D bucket) every probe missed L2, 50 ns per facet.
  template <class Visit>
  bool match_bucket(std::size_t b, std::size_t lo, std::size_t hi, const Buffer &buffer,
                    const Fine &fine, MatchTable &table,
                    std::vector<std::pair<std::uint16_t, Packed>> &singles, Visit &visit) const {
    const std::size_t n = hi - lo;
    int split = 0; // 2^split pieces
    while (split < shift && (n >> split) > g_match_piece)
      ++split;
    std::size_t pairs = 0;
    singles.clear();
    if (split == 0) {
      if (!match_range(buffer.data() + lo, FineInKey ? nullptr : fine.data() + lo, n, table,
                       singles, pairs))
        return false;
    } else {
      const int down = shift - split;
      const std::size_t pieces = std::size_t(1) << split;
      table.count.assign(pieces + 1, 0);
      if constexpr (FineInKey) {
        for (std::size_t i = lo; i < hi; ++i)
          ++table.count[(buffer[i] >> (kFineShift + down)) + 1];
      } else {
        for (std::size_t i = lo; i < hi; ++i)
          ++table.count[(fine[i] >> down) + 1];
      }
      for (std::size_t q = 1; q <= pieces; ++q)
        table.count[q] += table.count[q - 1];
      table.ids.resize(n);
      if constexpr (FineInKey) {
        for (std::size_t i = lo; i < hi; ++i)
          table.ids[table.count[buffer[i] >> (kFineShift + down)]++] = buffer[i];
      } else {
        table.fine.resize(n);
        for (std::size_t i = lo; i < hi; ++i) {
          const std::uint32_t at = table.count[fine[i] >> down]++;
          table.ids[at] = buffer[i];
          table.fine[at] = fine[i];
        }
      }
      // count[q] is now the end of piece q.
      for (std::size_t q = 0, from = 0; q < pieces; ++q) {
        const std::size_t to = table.count[q];
        if (to > from &&
            !match_range(table.ids.data() + from, FineInKey ? nullptr : table.fine.data() + from,
                         to - from, table, singles, pairs))
          return false;
        from = to;
      }
    }
    std::array<VertexId, K> key;
    std::uint32_t ref;
    for (const auto &[f, packed] : singles) {
      key[0] = VertexId((b << shift) + f);
      const Packed rest = packed >> kRefBits;
      for (int t = K - 1; t >= 1; --t)
        key[t] =
            VertexId((rest >> (kIdBits * (K - 1 - t))) & Packed(0xFFFFFFFFu >> (32 - kIdBits)));
      ref = (packed & 1u) ? kSideBit : 0u;
      visit(std::as_const(key), &ref, 1);
    }
    visit.interior_pairs(pairs);
    return true;
  }

  // Fills the chunk [b0, b1) of coarse buckets and visits it. visitor(k)
  // gives the visitor of block k, the coarse buckets [k * kBlock,
  // (k + 1) * kBlock); with Parallel the blocks are visited by several
  // threads at once (each block's visitor by one thread, in key order),
  // otherwise in order by this one.
  // `index`: the chunk's place in the walk's chunks (0 first).
  template <bool Parallel, class VisitorOf>
  void chunk(std::size_t b0, std::size_t b1, Buffers &buffers, VisitorOf &&visitor,
             std::size_t index) const {
    const std::size_t coarse = start.size() - 1;
    const std::size_t base = start[b0];
    const VertexId lo_v = VertexId(b0 << shift);
    const VertexId hi_v = VertexId(std::min(mesh.num_vertices(), b1 << shift));
    const std::size_t mask = (std::size_t(1) << shift) - 1;
    Buffer &buffer = buffers.packed;
    Fine &fine = buffers.fine;
    buffer.resize(start[b1] - base);
    fine.resize(shift && !FineInKey ? buffer.size() : 0);
#pragma omp parallel for num_threads(parts) schedule(static, 1)
    for (int t = 0; t < parts; ++t) {
      std::vector<std::size_t> cursor(b1 - b0);
      for (std::size_t b = b0; b < b1; ++b) {
        cursor[b - b0] = start[b] - base;
        for (int u = 0; u < t; ++u)
          cursor[b - b0] += counts[std::size_t(u) * coarse + b];
      }
      std::array<VertexId, K> key;
      // Local copies of the arrays' addresses: a store through a byte
      // pointer (the chunk pairs) may alias any object, so g++ reloaded the
      // vectors' data pointers (and the mesh's dimension) after each.
      const VertexId *const cells = mesh.cells.data();
      std::uint8_t *const pairs = buffers.pairs.empty() ? nullptr : buffers.pairs.data();
      const std::uint8_t *const chunk_of = buffers.chunk_of.data();
      const std::int8_t *const sign_of = signs ? signs->data() : nullptr;
      Packed *const out = buffer.data();
      std::uint16_t *const fine_out = fine.data();
      std::size_t *const cur = cursor.data();
      const int shift = this->shift;
      for (std::size_t c = part_begin(t), end = part_begin(t + 1); c < end; ++c) {
        const VertexId *cell = cells + c * std::size_t(Dim + 1);
        if constexpr (K == Dim && WithRefs) {
          // Facets from the cell's sorted ids: facet k omits the k-th
          // smallest, keeps the others in order, and its side follows from
          // the sort's parity (see facet_side).
          // Most cells have no facet in a chunk: the two smallest ids
          // decide that, without the sort.
          if (pairs && index > 0 && pairs[2 * c] != std::uint8_t(index) &&
              pairs[2 * c + 1] != std::uint8_t(index))
            continue;
          const auto [first, second] = two_smallest<Dim + 1>(cell);
          if (pairs && index == 0) {
            pairs[2 * c] = chunk_of[first >> shift];
            pairs[2 * c + 1] = chunk_of[second >> shift];
          }
          if (first >= hi_v || second < lo_v)
            continue;
          std::array<std::uint64_t, Dim + 1> keys;
          const int parity = sort_cell<Dim + 1>(cell, keys);
          std::array<VertexId, Dim + 1> ids;
          for (int i = 0; i <= Dim; ++i)
            ids[i] = VertexId(keys[i] >> 3);
          const int sign = sign_of ? sign_of[c] : 0;
          auto facet = [&](int k) {
            Packed p = 0;
            for (int i = 0, j = 0; i <= Dim; ++i)
              if (i != k && j++ > 0)
                p = (p << kIdBits) | ids[i];
            const bool positive = (parity + Dim - k) % 2 ? sign < 0 : sign > 0;
            if constexpr (SideOnly)
              return Packed((p << 1) | unsigned(positive));
            else if constexpr (CellRefs)
              return Packed((p << kRefBits) | (Packed(c) << 1) | unsigned(positive));
            else
              return Packed((p << 32) |
                            (std::uint32_t(c * M + (keys[k] & 7u)) | (positive ? kSideBit : 0u)));
          };
          // Facet 0 (without the smallest id) goes to the second smallest
          // id's bucket, facets 1..Dim side by side to the smallest's.
          if (ids[1] >= lo_v && ids[1] < hi_v) {
            const std::size_t at = cur[(ids[1] >> shift) - b0]++;
            if constexpr (FineInKey) {
              out[at] = facet(0) | (Packed(ids[1] & mask) << kFineShift);
            } else {
              out[at] = facet(0);
              if (shift)
                fine_out[at] = std::uint16_t(ids[1] & mask);
            }
          }
          if (ids[0] >= lo_v && ids[0] < hi_v) {
            std::size_t &end = cur[(ids[0] >> shift) - b0];
            const std::size_t at = end;
            end += Dim;
            if constexpr (FineInKey) {
              const Packed high = Packed(ids[0] & mask) << kFineShift;
              for (int k = 1; k <= Dim; ++k)
                out[at + k - 1] = facet(k) | high;
            } else {
              for (int k = 1; k <= Dim; ++k) {
                out[at + k - 1] = facet(k);
                if (shift)
                  fine_out[at + k - 1] = std::uint16_t(ids[0] & mask);
              }
            }
          }
          continue;
        }
        if constexpr (!FineInKey)
          for (int m = 0; m < M; ++m) {
            const VertexId low = min_of(cell, m);
            if (low < lo_v || low >= hi_v)
              continue;
            const std::size_t at = cursor[(low >> shift) - b0]++;
            buffer[at] = pack(cell, c, m, key);
            if (shift)
              fine[at] = std::uint16_t(low & mask);
          }
      }
    }
    const std::size_t k0 = b0 / kBlock, k1 = (b1 - 1) / kBlock + 1;
    // As many workers as scan parts: small meshes stay in this thread.
    const int workers = Parallel ? int(std::min<std::size_t>(std::size_t(parts), k1 - k0)) : 1;
#pragma omp parallel num_threads(workers)
    {
      std::vector<std::uint32_t> group;
      Buffer scratch;
      std::vector<std::size_t> count(mask + 2);
      MatchTable table;
      std::vector<std::pair<std::uint16_t, Packed>> singles;
#pragma omp for schedule(dynamic, 1)
      for (std::size_t k = k0; k < k1; ++k) {
        auto &visit = visitor(k);
        for (std::size_t b = std::max(b0, k * kBlock); b < std::min(b1, (k + 1) * kBlock); ++b) {
          const std::size_t lo = start[b] - base, hi = start[b + 1] - base;
          if (lo == hi)
            continue;
          if (!shift) {
            visit_bucket(VertexId(b), buffer.begin() + std::ptrdiff_t(lo),
                         buffer.begin() + std::ptrdiff_t(hi), group, visit);
            continue;
          }
          if constexpr (requires { visit.interior_pairs(std::size_t()); })
            if (!g_sorted_final_walk &&
                match_bucket(b, lo, hi, buffer, fine, table, singles, visit))
              continue;
          auto fine_at = [&](std::size_t i) {
            if constexpr (FineInKey)
              return fine_of(buffer[i]);
            else
              return fine[i];
          };
          std::fill(count.begin(), count.end(), 0);
          for (std::size_t i = lo; i < hi; ++i)
            ++count[fine_at(i) + 1];
          for (std::size_t f = 1; f < count.size(); ++f)
            count[f] += count[f - 1];
          scratch.resize(hi - lo);
          for (std::size_t i = lo; i < hi; ++i)
            scratch[count[fine_at(i)]++] = buffer[i];
          // count[f] is now the end of fine bucket f (and the start of f + 1).
          std::size_t from = 0;
          for (std::size_t f = 0; f <= mask && from < scratch.size(); ++f) {
            const std::size_t to = count[f];
            if (to > from)
              visit_bucket(VertexId((b << shift) + f), scratch.begin() + std::ptrdiff_t(from),
                           scratch.begin() + std::ptrdiff_t(to), group, visit);
            from = to;
          }
        }
      }
    }
  }
};

// Calls visit(key, refs, count) once per distinct K-vertex sub-simplex of the
// cells, with `key` its sorted vertex ids and refs[0..count) the references
// cell * M + m (M sub-simplices per cell, numbered by subsimplices()).
// Sub-simplices come in increasing key order. With `signs` (per-cell
// orientation; facets only, K == Dim) bit 31 of each reference is set when
// the facet's opposite vertex lies on the positive side of the facet (see
// facet_side), so the visitor never has to look the cell up again.
//
// Counting sort by smallest id (two levels, see Walk), in chunks of
// consecutive smallest ids so the buffer stays below kChunkBytes: each chunk
// scans the cells (sequentially) and stores, per sub-simplex whose smallest
// id falls in the chunk, one integer packing the other K-1 ids and the
// reference, high to low bits, and 2 bytes placing it in its coarse bucket.
// Sorting a bucket of those integers groups equal sub-simplices; the cells
// are never visited in random order.
//
// SideOnly (facets, with `signs`, fewer than 2^31 vertices): refs[i] holds
// only the side bit (kSideBit or 0), and the buffer packs the other ids in 31
// bits each plus that bit: half the memory for tets (the final check).
// WithRefs = false: only counts matter (refs is nullptr), the buffer holds the
// K-1 ids alone.
template <int Dim, int K, bool WithRefs = true, bool SideOnly = false, class Visit>
void for_each_subsimplex(const Mesh &mesh, Visit &&visit,
                         const std::vector<std::int8_t> *signs = nullptr) {
  using W = Walk<Dim, K, WithRefs, SideOnly>;
  const W walk(mesh, signs);
  const auto chunks = walk.chunks(W::entries_in(kChunkBytes));
  auto buffers = walk.buffers_for(chunks);
  for (std::size_t i = 0; i < chunks.size(); ++i)
    walk.template chunk<false>(
        chunks[i].first, chunks[i].second, buffers, [&](std::size_t) -> auto & { return visit; },
        i);
}

// The same walk with the visiting shared by the threads: `visitors` is
// resized to one copy of `prototype` per block of the walk (a piece fixed by
// the mesh alone), and visitors[k] sees block k's sub-simplices in key order;
// the caller combines the visitors' results in index order, which gives the
// same result for every thread count.
template <int Dim, int K, bool WithRefs = true, bool SideOnly = false,
          int IdBits = SideOnly ? 31 : 32, bool FineInKey = false, bool CellRefs = false,
          class Visitor>
void for_each_subsimplex_blocks(const Mesh &mesh, const Visitor &prototype,
                                std::vector<Visitor> &visitors,
                                const std::vector<std::int8_t> *signs = nullptr,
                                std::size_t chunk_bytes = kChunkBytes) {
  using W = Walk<Dim, K, WithRefs, SideOnly, IdBits, FineInKey, CellRefs>;
  const W walk(mesh, signs);
  visitors.assign((walk.start.size() - 1 + W::kBlock - 1) / W::kBlock, prototype);
  const auto chunks = walk.chunks(W::entries_in(chunk_bytes));
  auto buffers = walk.buffers_for(chunks);
  for (std::size_t i = 0; i < chunks.size(); ++i)
    walk.template chunk<true>(
        chunks[i].first, chunks[i].second,
        buffers, [&](std::size_t k) -> auto & { return visitors[k]; }, i);
}

template <int Dim, int K> std::size_t count_subsimplices(const Mesh &mesh) {
  std::size_t n = 0;
  for_each_subsimplex<Dim, K, false>(mesh, [&](const auto &, const std::uint32_t *, int) { ++n; });
  return n;
}

// ---- small geometry ---------------------------------------------------------

using geometry::squared_distance;

// Solves the n x n system G X = B (n <= 4) for `rhs` right-hand sides (B and
// X row-major, n x rhs) by elimination with pivoting; false when G is
// singular. Each column gets the very operations it would get alone (the
// pivots and multipliers depend on G only), so one call for the n columns of
// the identity gives the inverse in the numbers of n single solves.
bool small_solve(double *g, double *b, int n, double *x, int rhs = 1) {
  for (int k = 0; k < n; ++k) {
    int p = k;
    for (int i = k + 1; i < n; ++i)
      if (std::abs(g[i * n + k]) > std::abs(g[p * n + k]))
        p = i;
    if (!(std::abs(g[p * n + k]) > 0))
      return false;
    if (p != k) {
      for (int j = 0; j < n; ++j)
        std::swap(g[k * n + j], g[p * n + j]);
      for (int c = 0; c < rhs; ++c)
        std::swap(b[k * rhs + c], b[p * rhs + c]);
    }
    for (int i = k + 1; i < n; ++i) {
      const double f = g[i * n + k] / g[k * n + k];
      for (int j = k; j < n; ++j)
        g[i * n + j] -= f * g[k * n + j];
      for (int c = 0; c < rhs; ++c)
        b[i * rhs + c] -= f * b[k * rhs + c];
    }
  }
  for (int c = 0; c < rhs; ++c)
    for (int k = n - 1; k >= 0; --k) {
      double s = b[k * rhs + c];
      for (int j = k + 1; j < n; ++j)
        s -= g[k * n + j] * x[j * rhs + c];
      x[k * rhs + c] = s / g[k * n + k];
    }
  return true;
}

// (Dim-1)-measure of the facet with vertex rows p[0..Dim): the product of the
// edge vectors' orthogonalised lengths over (Dim-1)!, by modified Gram-Schmidt
// taking the longest remaining vector first. The Gram determinant would square
// the facet's condition number, and a facet of a cell stretched 200:1 then
// loses six digits (fuzz finding check-failed-stretched-4d).
template <int Dim> double facet_measure(const double *p) {
  constexpr int n = Dim - 1;
  double e[n][Dim];
  double len2[n];
  for (int i = 0; i < n; ++i) {
    len2[i] = 0;
    for (int d = 0; d < Dim; ++d) {
      e[i][d] = p[(i + 1) * Dim + d] - p[d];
      len2[i] += e[i][d] * e[i][d];
    }
  }
  double measure = 1;
  for (int k = 0; k < n; ++k) {
    int q = k;
    for (int i = k + 1; i < n; ++i)
      if (len2[i] > len2[q])
        q = i;
    if (q != k) {
      std::swap(e[k], e[q]);
      std::swap(len2[k], len2[q]);
    }
    double norm2 = 0;
    for (int d = 0; d < Dim; ++d)
      norm2 += e[k][d] * e[k][d];
    const double norm = std::sqrt(norm2);
    if (!(norm > 0))
      return 0;
    measure *= norm;
    for (int i = k + 1; i < n; ++i) {
      double dot = 0;
      for (int d = 0; d < Dim; ++d)
        dot += e[i][d] * e[k][d];
      const double f = dot / norm2;
      len2[i] = 0;
      for (int d = 0; d < Dim; ++d) {
        e[i][d] -= f * e[k][d];
        len2[i] += e[i][d] * e[i][d];
      }
    }
  }
  for (int i = 2; i <= n; ++i)
    measure /= i;
  return measure;
}

template <int Dim> double longest_squared_edge(const double *p) {
  double l = 0;
  for (int i = 0; i <= Dim; ++i)
    for (int j = i + 1; j <= Dim; ++j)
      l = std::max(l, squared_distance<Dim>(p + i * Dim, p + j * Dim));
  return l;
}

// 1e-14 * l^Dim for a squared length l2 (the degeneracy threshold).
template <int Dim> double degeneracy_bound(double l2) {
  double ln = Dim % 2 ? std::sqrt(l2) : 1; // l^Dim
  for (int i = 0; i < Dim / 2; ++i)
    ln *= l2;
  return 1e-14 * ln;
}

// Degenerate: |vol| <= 1e-14 * (longest edge)^n.
template <int Dim> bool degenerate(const double *p, double volume) {
  return !(std::abs(volume) > degeneracy_bound<Dim>(longest_squared_edge<Dim>(p)));
}

// The squared diagonal of the points' bounding box, which no edge passes
// (also in rounding: each coordinate difference and sum is monotone).
template <int Dim> double squared_diagonal(const Mesh &mesh) {
  double lo[Dim], hi[Dim];
  for (int k = 0; k < Dim; ++k)
    lo[k] = hi[k] = mesh.num_vertices() ? mesh.point(0)[k] : 0.0;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < Dim; ++k) {
      const double x = mesh.point(VertexId(v))[k];
      lo[k] = std::min(lo[k], x);
      hi[k] = std::max(hi[k], x);
    }
  double d2 = 0;
  for (int k = 0; k < Dim; ++k)
    d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
  return d2;
}

// Tolerance for "x lies on a facet", relative to the facet's longest edge and
// in barycentric coordinates.
constexpr double kOnFacetTol = 1e-8;

// Whether point x lies in the closed facet p[0..Dim) (rows): its distance to
// the facet's affine hull is tiny and its barycentric coordinates are >= 0.
template <int Dim> bool on_facet(const double *p, const double *x) {
  constexpr int n = Dim - 1;
  double e[n][Dim], d[Dim];
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < Dim; ++k)
      e[i][k] = p[(i + 1) * Dim + k] - p[k];
  for (int k = 0; k < Dim; ++k)
    d[k] = x[k] - p[k];
  double g[n * n], b[n], lambda[n];
  double size2 = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double s = 0;
      for (int k = 0; k < Dim; ++k)
        s += e[i][k] * e[j][k];
      g[i * n + j] = s;
    }
    double s = 0;
    for (int k = 0; k < Dim; ++k)
      s += e[i][k] * d[k];
    b[i] = s;
  }
  for (int i = 0; i < Dim; ++i)
    for (int j = i + 1; j < Dim; ++j)
      size2 = std::max(size2, squared_distance<Dim>(p + i * Dim, p + j * Dim));
  if (!small_solve(g, b, n, lambda))
    return false;
  double rest = 1, r2 = 0;
  for (int i = 0; i < n; ++i) {
    if (lambda[i] < -kOnFacetTol)
      return false;
    rest -= lambda[i];
  }
  if (rest < -kOnFacetTol)
    return false;
  for (int k = 0; k < Dim; ++k) {
    double r = d[k];
    for (int i = 0; i < n; ++i)
      r -= lambda[i] * e[i][k];
    r2 += r * r;
  }
  return r2 <= kOnFacetTol * kOnFacetTol * size2;
}

// floor(t) within [0, n - 1]; 0 for NaN, which a coordinate difference
// over a grid cell's size gives where both are infinite (coordinates near
// the ends of the double range).
inline std::int64_t grid_cell(double t, std::int64_t n) {
  if (!(t >= 0))
    return 0;
  if (!(t < double(n - 1)))
    return n - 1;
  return std::int64_t(t);
}

template <int Dim> void gather(const Mesh &mesh, const VertexId *ids, int count, double *out) {
  for (int k = 0; k < count; ++k) {
    const double *q = mesh.point(ids[k]);
    for (int d = 0; d < Dim; ++d)
      out[k * Dim + d] = q[d];
  }
}

// ---- messages ---------------------------------------------------------------

// Vertices, cells and faces are named through core/names.hpp: indices, or
// a .msh input's node and element tags.
template <std::size_t K> std::string id_list(const Mesh &mesh, const std::array<VertexId, K> &key) {
  return face_ids(mesh, key.data(), int(K));
}

std::string id_list(const Mesh &mesh, const VertexId *ids, int count) {
  return face_ids(mesh, ids, count);
}

std::string format(const char *fmt, double a, double b, double c) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

// ---- the passes -------------------------------------------------------------

// What one walk over the facets finds.
struct FacetReport {
  std::size_t facets = 0;          // distinct facets
  std::size_t boundary_facets = 0; // owned by one cell
  double boundary_measure = 0;
  double smallest_boundary_facet = INFINITY; // measure
  std::vector<VertexId> boundary;            // Dim sorted ids per boundary facet
  std::vector<VertexId> boundary_opposite;   // per boundary facet: its cell's other vertex
  std::string
      nonmanifold; // first facet shared by 3+ cells, e.g. "facet (1, 2, 3) is shared by 3 cells"
  std::string overlap; // first folded pair, e.g. "cells 5 and 9 overlap across facet (1, 2, 3)"
  std::vector<std::array<CellId, 2>> interior; // with keep_interior: see InteriorFacets
};

// Side of the facet's hyperplane on which the opposite vertex of facet m of
// cell c lies, i.e. the sign of orient(facet ids sorted, opposite vertex).
// That tuple is a permutation of the cell's tuple, so the sign is the cell's
// orientation times the permutation's parity: moving the opposite vertex from
// local position j to the end takes Dim - j transpositions, sorting the rest
// one per inversion. No geometry beyond the cell's own sign is needed.
template <int Dim> int facet_side(const VertexId *cell, int m, int cell_sign) {
  const int j = opposite_of_facet<Dim>(m);
  std::array<VertexId, Dim> rest;
  for (int i = 0, k = 0; i <= Dim; ++i)
    if (i != j)
      rest[k++] = cell[i];
  int parity = Dim - j;
  for (int i = 0; i < Dim; ++i)
    for (int k = i + 1; k < Dim; ++k)
      parity += rest[i] > rest[k];
  return parity % 2 ? -cell_sign : cell_sign;
}

// One walk over the distinct facets. With `signs` (per-cell orientation,
// 0 for degenerate cells) it also checks that across every interior facet
// the two opposite vertices lie on opposite sides of the facet's hyperplane.
// SideOnly (needs `signs` without degenerate cells): the lighter walk of the
// final check; an overlap is reported by its facet only.
// The facet visitor of facet_pass, accumulating into `r`.
template <int Dim, bool SideOnly> struct FacetVisitor {
  const Mesh *mesh;
  const std::vector<std::int8_t> *signs;
  bool keep_boundary;
  FacetReport r;
  bool keep_interior = false;
  // Interior facets matched without a visit (the final check's fast path).
  void interior_pairs(std::size_t n) requires SideOnly { r.facets += n; }
  void operator()(const std::array<VertexId, Dim> &key, const std::uint32_t *refs, int count) {
    constexpr int M = Dim + 1;
    ++r.facets;
    if (count == 1) {
      ++r.boundary_facets;
      double pts[Dim * Dim];
      gather<Dim>(*mesh, key.data(), Dim, pts);
      const double measure = facet_measure<Dim>(pts);
      r.boundary_measure += measure;
      r.smallest_boundary_facet = std::min(r.smallest_boundary_facet, measure);
      if (keep_boundary) {
        r.boundary.insert(r.boundary.end(), key.begin(), key.end());
        // The cell's vertex off the facet (a narrow walk's reference has
        // the cell only).
        const VertexId *cell = mesh->cell(CellId((refs[0] & ~kSideBit) / M));
        r.boundary_opposite.push_back(*std::find_if(cell, cell + M, [&](VertexId v) {
          return std::find(key.begin(), key.end(), v) == key.end();
        }));
      }
    } else if (count == 2) {
      if constexpr (!SideOnly)
        if (keep_interior) {
          const CellId a = CellId((refs[0] & ~kSideBit) / M), b = CellId((refs[1] & ~kSideBit) / M);
          r.interior.push_back({std::min(a, b), std::max(a, b)});
        }
      if (!signs || !r.overlap.empty())
        return;
      if constexpr (SideOnly) {
        if (refs[0] == refs[1])
          r.overlap = "two cells overlap across facet " + id_list(*mesh, key);
        return;
      }
      const CellId cells[2] = {CellId((refs[0] & ~kSideBit) / M),
                               CellId((refs[1] & ~kSideBit) / M)};
      // Degenerate cells (sign 0) are reported before this pass; skip them.
      if ((*signs)[cells[0]] == 0 || (*signs)[cells[1]] == 0)
        return;
      if ((refs[0] & kSideBit) == (refs[1] & kSideBit))
        r.overlap = cell_pair_name(*mesh, cells[0], cells[1]) + " overlap across facet " +
                    id_list(*mesh, key);
    } else if (r.nonmanifold.empty()) {
      r.nonmanifold =
          "facet " + id_list(*mesh, key) + " is shared by " + std::to_string(count) + " cells";
    }
  }
};

// With `interior`, the facets shared by two cells are recorded there
// (InteriorFacets in check.hpp), one piece per block of the walk.
// In 3D, with references, the walk is a narrow one (CellRefs) where the ids
// fit: the same visits, in half the memory.
template <int Dim, bool SideOnly = false, int IdBits = SideOnly ? 31 : 32, bool FineInKey = false>
FacetReport facet_pass(const Mesh &mesh, const std::vector<std::int8_t> *signs, bool keep_boundary,
                       InteriorFacets *interior = nullptr, std::size_t chunk_bytes = kChunkBytes) {
  std::vector<FacetVisitor<Dim, SideOnly>> parts;
  const FacetVisitor<Dim, SideOnly> prototype{&mesh, signs, keep_boundary, {}, interior != nullptr};
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  if constexpr (Dim == 3 && !SideOnly && IdBits == 32 && !FineInKey) {
    if (g_narrow_facet_walk && Walk<Dim, Dim, true, false, 20, false, true>::fits(nv, nc))
      for_each_subsimplex_blocks<Dim, Dim, true, false, 20, false, true>(mesh, prototype, parts,
                                                                         signs, chunk_bytes);
    else if (g_narrow_facet_walk && Walk<Dim, Dim, true, false, 18, false, true>::fits(nv, nc))
      for_each_subsimplex_blocks<Dim, Dim, true, false, 18, false, true>(mesh, prototype, parts,
                                                                         signs, chunk_bytes);
    else
      for_each_subsimplex_blocks<Dim, Dim, true, SideOnly, IdBits, FineInKey>(
          mesh, prototype, parts, signs, chunk_bytes);
  } else {
    for_each_subsimplex_blocks<Dim, Dim, true, SideOnly, IdBits, FineInKey>(mesh, prototype, parts,
                                                                            signs, chunk_bytes);
  }
  if (interior) {
    interior->clear();
    for (auto &part : parts)
      interior->push_back(std::move(part.r.interior));
  }
  // In block order, which is key order: the same sums and the same first
  // finding as one walk in one thread.
  FacetReport r;
  for (auto &part : parts) {
    const FacetReport &p = part.r;
    r.facets += p.facets;
    r.boundary_facets += p.boundary_facets;
    r.boundary_measure += p.boundary_measure;
    r.smallest_boundary_facet = std::min(r.smallest_boundary_facet, p.smallest_boundary_facet);
    r.boundary.insert(r.boundary.end(), p.boundary.begin(), p.boundary.end());
    r.boundary_opposite.insert(r.boundary_opposite.end(), p.boundary_opposite.begin(),
                               p.boundary_opposite.end());
    if (r.nonmanifold.empty())
      r.nonmanifold = p.nonmanifold;
    if (r.overlap.empty())
      r.overlap = p.overlap;
  }
  return r;
}

// First cell with an id out of range, e.g. "cell 5 refers to vertex 99, but
// there are only 12 vertices"; empty when all ids are valid.
std::string check_ids(const Mesh &mesh) {
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  const int n = mesh.cell_size();
  for (std::size_t c = 0; c < nc; ++c)
    for (int k = 0; k < n; ++k)
      if (mesh.cells[c * n + k] >= nv)
        return "cell " + std::to_string(c) + " refers to vertex " +
               std::to_string(mesh.cells[c * n + k]) + ", but there are only " +
               std::to_string(nv) + " vertices";
  return {};
}

std::string check_shape(const Mesh &mesh) {
  if (mesh.dim < 2 || mesh.dim > 4)
    return "unsupported dimension " + std::to_string(mesh.dim) + " (expected 2, 3 or 4)";
  if (mesh.coords.size() % mesh.dim != 0)
    return "coordinate array length " + std::to_string(mesh.coords.size()) +
           " is not a multiple of the dimension " + std::to_string(mesh.dim);
  if (mesh.cells.size() % (mesh.dim + 1) != 0)
    return "cell array length " + std::to_string(mesh.cells.size()) + " is not a multiple of " +
           std::to_string(mesh.dim + 1);
  return {};
}

// Sum of |volume|; `first_degenerate` set to the first degenerate cell (or
// -1); `signs`, when given, receives each cell's orientation (0 if degenerate).
// With `ids_ok`, the cells' ids are checked on the way, a block at a time
// before the block is read (a block with an id out of range is skipped and
// `ids_ok` set to false; check_ids names the cell), instead of by a serial
// pass of their own.
// With `quality`, the quality summary (min, max, mean of the mean ratio)
// as well, from the same determinants, summed in blocks: the same figures
// for every thread count.
template <int Dim>
double cell_pass(const Mesh &mesh, std::size_t &first_degenerate, double &its_volume,
                 std::vector<std::int8_t> *signs = nullptr, bool *ids_ok = nullptr,
                 QualitySummary *quality = nullptr) {
  // Blocks of kBlock cells, summed in block order: the same total for every
  // thread count.
  constexpr std::size_t kBlock = std::size_t(1) << 14, kAhead = 8;
  const std::size_t nc = mesh.num_cells(), blocks = (nc + kBlock - 1) / kBlock;
  std::vector<double> sums(blocks, 0.0);
  std::vector<std::size_t> first(blocks, std::size_t(-1));
  std::vector<double> first_volume(blocks, 0.0);
  std::vector<std::uint8_t> out_of_range(ids_ok ? blocks : 0, 0);
  const std::size_t qblocks = quality ? blocks : 0;
  std::vector<double> q_lo(qblocks, 1e300), q_hi(qblocks, -1e300), q_sum(qblocks, 0.0);
  const std::size_t nv = mesh.num_vertices();
  if (signs)
    signs->assign(nc, 0);
  // Quality alone (quality_summary, after every iteration): no volume, no
  // degeneracy test.
  const bool quality_only = quality && !signs && !ids_ok;
  const double any_edge_bound =
      quality_only ? 0.0 : degeneracy_bound<Dim>(squared_diagonal<Dim>(mesh));
  const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t k = 0; k < blocks; ++k) {
    double pts[(Dim + 1) * Dim];
    double total = 0;
    const std::size_t end = std::min(nc, (k + 1) * kBlock);
    if (ids_ok) {
      const VertexId *ids = mesh.cell(CellId(k * kBlock));
      bool in_range = true;
      for (std::size_t i = 0; i < (end - k * kBlock) * (Dim + 1); ++i)
        in_range &= ids[i] < nv;
      if (!in_range) {
        out_of_range[k] = 1;
        continue;
      }
    }
    // The loop, with or without the quality summary. With the quality, cells
    // go kBatch at a time: their determinants and edge sums first, then
    // their mean ratios, whose cube roots (3D) and square roots (4D) are long
    // chains of dependent steps. A loop of them alone keeps several cells'
    // chains in flight; one gathering points between them did not (3D
    // benchmark, 13 iterations, one thread: the quality stage 2.6 -> 1.6 s;
    // a cube root in a third of glibc's time gained nothing more).
    auto walk = [&]<bool Quality, bool Check>() {
      constexpr std::size_t kBatch = Quality ? 16 : 1;
      double q_min = 1e300, q_max = -1e300, q_total = 0;
      double dets[kBatch], sums_sq[kBatch];
      for (std::size_t c0 = k * kBlock; c0 < end; c0 += kBatch) {
        const std::size_t c1 = std::min(end, c0 + kBatch);
        for (std::size_t c = c0; c < c1; ++c) {
          if (c + kAhead < end)
            geometry::prefetch_points<Dim>(mesh, CellId(c + kAhead));
          gather<Dim>(mesh, mesh.cell(CellId(c)), Dim + 1, pts);
          const double det = geometry::edge_determinant<Dim>(pts);
          if constexpr (Quality) {
            dets[c - c0] = det;
            sums_sq[c - c0] = geometry::squared_edge_sum<Dim>(pts);
          }
          if constexpr (Check) {
            const double v = det / geometry::factorial(Dim); // geometry::signed_volume
            total += std::abs(v);
            // Above the bound for the longest possible edge no cell is
            // degenerate: the cell's own edges are needed only below it.
            const bool bad = !(std::abs(v) > any_edge_bound) && degenerate<Dim>(pts, v);
            if (signs && !bad)
              (*signs)[c] = v > 0 ? 1 : -1;
            if (bad && first[k] == std::size_t(-1)) {
              first[k] = c;
              first_volume[k] = v;
            }
          }
        }
        if constexpr (Quality)
          for (std::size_t i = 0; i < c1 - c0; ++i) {
            const double q = geometry::mean_ratio_of<Dim>(dets[i], sums_sq[i]);
            q_min = std::min(q_min, q);
            q_max = std::max(q_max, q);
            q_total += q;
          }
      }
      if constexpr (Quality) {
        q_lo[k] = q_min;
        q_hi[k] = q_max;
        q_sum[k] = q_total;
      }
    };
    if (quality_only)
      walk.template operator()<true, false>();
    else if (quality)
      walk.template operator()<true, true>();
    else
      walk.template operator()<false, true>();
    sums[k] = total;
  }
  if (quality) {
    *quality = QualitySummary{1e300, -1e300, 0};
    double q_total = 0;
    for (std::size_t k = 0; k < blocks; ++k) {
      quality->min = std::min(quality->min, q_lo[k]);
      quality->max = std::max(quality->max, q_hi[k]);
      q_total += q_sum[k];
    }
    quality->mean = q_total / double(nc);
  }
  if (ids_ok)
    *ids_ok = std::find(out_of_range.begin(), out_of_range.end(), 1) == out_of_range.end();
  double total = 0;
  first_degenerate = std::size_t(-1);
  for (std::size_t k = 0; k < blocks; ++k) {
    total += sums[k];
    if (first_degenerate == std::size_t(-1) && first[k] != std::size_t(-1)) {
      first_degenerate = first[k];
      its_volume = first_volume[k];
    }
  }
  return total;
}

// V - E + F - ... over the vertices used by cells; `facets` is the number of
// distinct facets (already known from facet_pass), `ridges` that of the
// faces of Dim - 1 vertices when known (counted by find_fold in 3D and 4D).
template <int Dim>
long long euler_characteristic(const Mesh &mesh, std::size_t facets,
                               std::size_t ridges = std::size_t(-1)) {
  std::vector<char> used(mesh.num_vertices(), 0);
  for (VertexId v : mesh.cells)
    used[v] = 1;
  long long chi = std::count(used.begin(), used.end(), 1);
  long long sign = -1;
  auto add = [&](long long count) {
    chi += sign * count;
    sign = -sign;
  };
  if constexpr (Dim == 3)
    add((long long)(ridges != std::size_t(-1) ? ridges : count_subsimplices<Dim, 2>(mesh)));
  if constexpr (Dim == 4) {
    add((long long)count_subsimplices<Dim, 2>(mesh));
    add((long long)(ridges != std::size_t(-1) ? ridges : count_subsimplices<Dim, 3>(mesh)));
  }
  add((long long)facets);
  add((long long)mesh.num_cells());
  return chi;
}

// Calls visit(at) for every box `at` (K indices) of a K-dimensional grid
// from corner a to corner b, the first index fastest; stops when visit
// returns false.
template <int K, class Visit>
void for_each_box(const std::int64_t *a, const std::int64_t *b, Visit &&visit) {
  std::int64_t at[K];
  std::copy(a, a + K, at);
  while (true) {
    if (!visit(static_cast<const std::int64_t *>(at)))
      return;
    int k = 0;
    while (k < K && at[k] == b[k])
      at[k] = a[k], ++k;
    if (k == K)
      return;
    ++at[k];
  }
}

// The number of box `at` in a grid of n[k] boxes a side, the first index
// fastest.
template <int K> std::size_t box_number(const std::int64_t *at, const std::int64_t *n) {
  std::size_t g = 0;
  for (int k = K - 1; k >= 0; --k)
    g = g * std::size_t(n[k]) + std::size_t(at[k]);
  return g;
}

// Hanging nodes: a vertex lying on the closed boundary facet it does not
// belong to. In a conforming mesh the only vertices on a closed facet are its
// own (cells meet in common faces); a non-conforming interface shows up as
// boundary facets on both sides, so only boundary facets and boundary
// vertices need to be searched. Boundary vertices go into a uniform grid
// (cell size = mean facet extent) stored as sorted (cell key, vertex) pairs;
// each facet visits the grid cells its bounding box covers.
//
// Then the same search with the centroids of the boundary facets in place of
// the vertices: two cells that split their shared face differently without a
// hanging node (each side's sub-facets use the same vertices but other
// diagonals) leave two patches of boundary facets covering the same part of
// the face, so the centroid of one lies on a facet of the other. In a valid
// mesh a boundary facet's centroid is in its relative interior, which no
// other boundary facet meets (they share at most a proper face), so this
// never fires on a conforming mesh.
template <int Dim>
std::string find_hanging_node(const Mesh &mesh, const std::vector<VertexId> &bnd) {
  const std::size_t nb = bnd.size() / Dim;
  if (nb == 0)
    return {};
  std::vector<char> is_bnd(mesh.num_vertices(), 0);
  for (VertexId v : bnd)
    is_bnd[v] = 1;

  double lo[Dim], hi[Dim];
  std::fill(lo, lo + Dim, 1e300);
  std::fill(hi, hi + Dim, -1e300);
  for (std::size_t v = 0; v < is_bnd.size(); ++v)
    if (is_bnd[v])
      for (int d = 0; d < Dim; ++d) {
        lo[d] = std::min(lo[d], mesh.point(VertexId(v))[d]);
        hi[d] = std::max(hi[d], mesh.point(VertexId(v))[d]);
      }
  double h = 0;
  double pts[Dim * Dim];
  for (std::size_t f = 0; f < nb; ++f) {
    gather<Dim>(mesh, &bnd[f * Dim], Dim, pts);
    double ext = 0;
    for (int d = 0; d < Dim; ++d) {
      double a = pts[d], b = pts[d];
      for (int k = 1; k < Dim; ++k)
        a = std::min(a, pts[k * Dim + d]), b = std::max(b, pts[k * Dim + d]);
      ext = std::max(ext, b - a);
    }
    h += ext;
  }
  h /= double(nb);
  if (!(h > 0))
    return {};

  constexpr int kBits = 64 / Dim;
  constexpr double kMaxCells = double((std::uint64_t(1) << (kBits - 1)) - 1);
  double cell_size[Dim];
  std::int64_t ncell[Dim];
  for (int d = 0; d < Dim; ++d) {
    const double ext = hi[d] - lo[d];
    cell_size[d] = std::max(h, ext / kMaxCells);
    ncell[d] = std::int64_t(ext / cell_size[d]) + 1;
  }
  auto index = [&](double x, int d) { return grid_cell((x - lo[d]) / cell_size[d], ncell[d]); };
  auto key_of = [&](const std::int64_t *idx) {
    std::uint64_t k = 0;
    for (int d = 0; d < Dim; ++d)
      k |= std::uint64_t(idx[d]) << (kBits * d);
    return k;
  };

  // Pass 0: boundary vertices (payload: the vertex id); pass 1: centroids of
  // boundary facets (payload: the facet's index in bnd).
  std::vector<double> centroids(nb * Dim, 0.0);
  for (std::size_t f = 0; f < nb; ++f)
    for (int k = 0; k < Dim; ++k)
      for (int d = 0; d < Dim; ++d)
        centroids[f * Dim + d] += mesh.point(bnd[f * Dim + k])[d] / Dim;
  std::vector<std::pair<std::uint64_t, std::size_t>> grid;
  for (int pass = 0; pass < 2; ++pass) {
    grid.clear();
    auto point_of = [&](std::size_t payload) {
      return pass == 0 ? mesh.point(VertexId(payload)) : &centroids[payload * Dim];
    };
    auto add = [&](std::size_t payload) {
      std::int64_t idx[Dim];
      for (int d = 0; d < Dim; ++d)
        idx[d] = index(point_of(payload)[d], d);
      grid.push_back({key_of(idx), payload});
    };
    if (pass == 0) {
      for (std::size_t v = 0; v < is_bnd.size(); ++v)
        if (is_bnd[v])
          add(v);
    } else {
      for (std::size_t f = 0; f < nb; ++f)
        add(f);
    }
    std::sort(grid.begin(), grid.end());

    for (std::size_t f = 0; f < nb; ++f) {
      const VertexId *ids = &bnd[f * Dim];
      gather<Dim>(mesh, ids, Dim, pts);
      double flo[Dim], fhi[Dim], size2 = 0;
      for (int i = 0; i < Dim; ++i)
        for (int j = i + 1; j < Dim; ++j)
          size2 = std::max(size2, squared_distance<Dim>(pts + i * Dim, pts + j * Dim));
      const double pad = 2 * kOnFacetTol * std::sqrt(size2);
      std::int64_t ilo[Dim], ihi[Dim];
      double cover = 1;
      for (int d = 0; d < Dim; ++d) {
        flo[d] = fhi[d] = pts[d];
        for (int k = 1; k < Dim; ++k)
          flo[d] = std::min(flo[d], pts[k * Dim + d]), fhi[d] = std::max(fhi[d], pts[k * Dim + d]);
        flo[d] -= pad;
        fhi[d] += pad;
        ilo[d] = index(flo[d], d);
        ihi[d] = index(fhi[d], d);
        cover *= double(ihi[d] - ilo[d] + 1);
      }
      auto test = [&](std::size_t payload) {
        if (pass == 0 ? std::find(ids, ids + Dim, VertexId(payload)) != ids + Dim : payload == f)
          return false;
        const double *x = point_of(payload);
        for (int d = 0; d < Dim; ++d)
          if (x[d] < flo[d] || x[d] > fhi[d])
            return false;
        return on_facet<Dim>(pts, x);
      };
      auto report = [&](std::size_t payload) {
        if (pass == 0)
          return vertex_name(mesh, VertexId(payload)) + " lies on facet " +
                 id_list(mesh, ids, Dim) + " (hanging node)";
        return "boundary facets " + id_list(mesh, &bnd[payload * Dim], Dim) + " and " +
               id_list(mesh, ids, Dim) +
               " overlap: the cells on the two sides of a face split it differently";
      };
      if (cover > double(grid.size())) { // a huge facet: scanning everything is cheaper
        for (const auto &g : grid)
          if (test(g.second))
            return report(g.second);
        continue;
      }
      std::size_t found = std::size_t(-1);
      for_each_box<Dim>(ilo, ihi, [&](const std::int64_t *idx) {
        const std::uint64_t k = key_of(idx);
        auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(k, std::size_t(0)));
        for (; it != grid.end() && it->first == k; ++it)
          if (test(it->second)) {
            found = it->second;
            return false;
          }
        return true;
      });
      if (found != std::size_t(-1))
        return report(found);
    }
  }
  return {};
}

// Two vertices used by cells at exactly the same coordinates, as one line
// naming them (empty when there are none). O(n log n); run only to explain a
// failed check.
std::string find_duplicate_vertices(const Mesh &mesh) {
  std::vector<char> used(mesh.num_vertices(), 0);
  for (VertexId v : mesh.cells)
    used[v] = 1;
  std::vector<VertexId> order;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v])
      order.push_back(VertexId(v));
  const int d = mesh.dim;
  auto less = [&](VertexId a, VertexId b) {
    return std::lexicographical_compare(mesh.point(a), mesh.point(a) + d, mesh.point(b),
                                        mesh.point(b) + d);
  };
  std::sort(order.begin(), order.end(),
            [&](VertexId a, VertexId b) { return less(a, b) || (!less(b, a) && a < b); });
  std::size_t pairs = 0;
  VertexId first_a = 0, first_b = 0;
  for (std::size_t i = 1; i < order.size(); ++i)
    if (std::equal(mesh.point(order[i]), mesh.point(order[i]) + d, mesh.point(order[i - 1]))) {
      if (pairs++ == 0)
        first_a = order[i - 1], first_b = order[i];
    }
  if (pairs == 0)
    return {};
  std::string at;
  for (int k = 0; k < d; ++k)
    at += (k ? ", " : "") + format("%.17g", mesh.point(first_a)[k], 0, 0);
  return std::string("duplicate ") + vertex_word(mesh, true) + ": " + vertex_number(mesh, first_a) +
         " and " + vertex_number(mesh, first_b) + " are both at (" + at + ")" +
         (pairs > 1 ? " (and " + std::to_string(pairs - 1) + " more pairs)" : std::string()) +
         "; the cells on either side do not share them, so the mesh is not connected there "
         "(merge coincident nodes, e.g. with Gmsh's Coherence Mesh)";
}

// Two cells with the same vertices, asked only when a check has failed (a
// repeated cell makes its facets "shared by 4 cells"): the first pair by
// index, with their gmsh:physical tags when the mesh has them, since Gmsh's
// 2.2 format repeats an element once for each physical group it is in.
std::string find_duplicate_cells(const Mesh &mesh) {
  const std::size_t nc = mesh.num_cells(), n = std::size_t(mesh.cell_size());
  std::vector<VertexId> sorted(mesh.cells.begin(), mesh.cells.end());
  for (std::size_t c = 0; c < nc; ++c)
    std::sort(sorted.begin() + std::ptrdiff_t(c * n), sorted.begin() + std::ptrdiff_t((c + 1) * n));
  std::vector<CellId> order(nc);
  std::iota(order.begin(), order.end(), CellId(0));
  auto key = [&](CellId c) { return sorted.begin() + std::ptrdiff_t(std::size_t(c) * n); };
  std::sort(order.begin(), order.end(), [&](CellId a, CellId b) {
    const int cmp = std::memcmp(&*key(a), &*key(b), n * sizeof(VertexId)); // any fixed order
    return cmp != 0 ? cmp < 0 : a < b;
  });
  std::size_t pairs = 0;
  CellId a = 0, b = 0;
  for (std::size_t i = 1; i < nc; ++i)
    if (std::equal(key(order[i]), key(order[i]) + std::ptrdiff_t(n), key(order[i - 1])) &&
        (pairs++ == 0 || std::make_pair(order[i - 1], order[i]) < std::make_pair(a, b)))
      a = order[i - 1], b = order[i];
  if (pairs == 0)
    return {};
  std::string tags, why;
  for (const DataArray &d : mesh.cell_data)
    if (d.name == "gmsh:physical" && d.components == 1 && d.values.size() == nc &&
        d.values[a] != d.values[b]) {
      tags = format(", with gmsh:physical %.17g and %.17g", d.values[a], d.values[b], 0);
      why = ": Gmsh's .msh 2.2 repeats an element for each physical group it is in, and a cell "
            "is in one group here; give the region one Physical group, or save as .msh 4.1, "
            "where a cell keeps its entity's first group";
    }
  return "duplicate cells: " + cell_pair_name(mesh, a, b) + " have the same vertices" + tags +
         (pairs > 1 ? " (and " + with_commas(pairs - 1) + " more pairs)" : std::string()) + why;
}

// Cells overlapping without sharing a facet (which the facet pass cannot see):
// in a valid mesh the centroid of a cell lies in no other cell. Each cell
// tests the centroids in its bounding box; the first cell (by index) with a
// centroid strictly inside is reported, with the smallest such centroid's
// cell. Not a proof of validity (two thin crossing cells may keep their
// centroids apart), but exact in what it reports. A cell whose box covers
// more than 4096 * 2^Dim cells of a grid of half the mean cell extent (a
// huge cell among small ones) is skipped.
//
// Linear-time range search on a Z-order (Morton) curve, which adapts to
// graded meshes by itself (a uniform grid of one size did not: big cells
// covered many of its cells, small ones crowded into few): the centroids'
// coordinates are quantized to 64 / Dim bits each and interleaved into one
// key, and the centroids are sorted by key (counting sort on the top bits,
// then each bucket in the cache). Every point of a box has its key between
// the keys of the box's corners, and runs of keys outside the box are
// skipped with BIGMIN (Tropf and Herzog, "Multidimensional range search in
// dynamically balanced trees", 1981): the smallest key past a given one
// that lies in the box. Cells query in groups, the leaves of an octree
// over the sorted keys (at most 2,048 centroids of one aligned Z cell): one
// range search finds the centroids near the group (its centroids' box
// widened by the group's mean cell extent), a small grid of about two of
// them a cell sorts them, and each cell reads the grid cells its box
// covers; a cell whose box passes the widened box (a large one at the
// group's edge) makes its own range search. A range search per cell, as
// before, scanned 164 keys and made 4.6 BIGMIN jumps a cell on the 3.2 M-tet
// ball. Each group keeps its smallest finding, so the result is the same
// for every thread count and every grouping (tested against the search per
// cell and against brute force on meshes with cells laid over them).
template <int Dim> struct ZOrder {
  static constexpr int kBits = 64 / Dim; // per coordinate
  static constexpr int kKeyBits = kBits * Dim;
  using Key = std::uint64_t;

  // spread[b]: the 8 bits of b moved to bits 0, Dim, 2 Dim, ...
  std::array<Key, 256> spread{};
  std::array<Key, Dim> axis{}; // the key bits of each coordinate

  ZOrder() {
    for (int b = 0; b < 256; ++b)
      for (int i = 0; i < 8; ++i)
        if (b >> i & 1)
          spread[std::size_t(b)] |= Key(1) << (i * Dim);
    for (int d = 0; d < Dim; ++d)
      for (int i = 0; i < kBits; ++i)
        axis[std::size_t(d)] |= Key(1) << (i * Dim + d);
  }

  Key key(const std::uint32_t *q) const {
    Key k = 0;
    for (int d = 0; d < Dim; ++d)
      for (int j = 0; j * 8 < kBits; ++j)
        k |= spread[(q[d] >> (8 * j)) & 255u] << (8 * j * Dim + d);
    return k;
  }

  // Whether key k lies in the box of corner keys lo, hi: coordinate by
  // coordinate, the masked keys compare as the coordinates do.
  bool inside(Key k, Key lo, Key hi) const {
    bool in = true; // without branches: the outcome is hard to predict
    for (int d = 0; d < Dim; ++d) {
      const Key m = axis[std::size_t(d)];
      in &= ((k & m) >= (lo & m)) & ((k & m) <= (hi & m));
    }
    return in;
  }

  // BIGMIN: the smallest key greater than z inside the box of corner keys
  // lo <= z <= hi, z outside the box; ~0 when there is none.
  Key next_inside(Key z, Key lo, Key hi) const {
    Key best = ~Key(0);
    const Key differ = lo ^ hi;
    if (!differ)
      return best;
    for (int b = 63 - __builtin_clzll(differ); b >= 0; --b) {
      const Key bit = Key(1) << b;
      const Key below = axis[std::size_t(b % Dim)] & (bit - 1); // same coordinate, lower bits
      const int case_ = int((z & bit) != 0) << 2 | int((lo & bit) != 0) << 1 | int((hi & bit) != 0);
      switch (case_) {
      case 0b001: // z's side is the low half: the box's high half starts after z
        best = (lo | bit) & ~below;
        hi = (hi & ~bit) | below;
        break;
      case 0b011: // the whole box is above z
        return lo;
      case 0b100: // the whole box is below z
        return best;
      case 0b101: // z in the high half: only the box's high half can follow
        lo = (lo | bit) & ~below;
        break;
      default: // 000, 111: z in the box's one half; 010, 110 cannot happen
        break;
      }
    }
    return best;
  }
};

// Sorts `keys` (with `ids` alongside) by key: a counting sort on the top 16
// bits, then each bucket on its own (in the cache), buckets in parallel.
inline void sort_by_key(std::vector<std::uint64_t> &keys, std::vector<CellId> &ids, int key_bits) {
  const std::size_t n = keys.size();
  const int shift = std::max(0, key_bits - 16);
  const std::size_t buckets = (std::size_t(1) << std::min(key_bits, 16)) + 1;
  std::vector<std::size_t> start(buckets + 1, 0);
  for (std::uint64_t k : keys)
    ++start[(k >> shift) + 1];
  for (std::size_t b = 1; b <= buckets; ++b)
    start[b] += start[b - 1];
  std::vector<std::pair<std::uint64_t, CellId>,
              UninitialisedAllocator<std::pair<std::uint64_t, CellId>>>
      sorted(n);
  {
    std::vector<std::size_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      sorted[cursor[keys[i] >> shift]++] = {keys[i], ids[i]};
  }
  const int workers = int(std::clamp<std::size_t>(n >> 16, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 64)
  for (std::size_t b = 0; b < buckets; ++b) {
    std::sort(sorted.begin() + std::ptrdiff_t(start[b]),
              sorted.begin() + std::ptrdiff_t(start[b + 1]));
    for (std::size_t i = start[b]; i < start[b + 1]; ++i) {
      keys[i] = sorted[i].first;
      ids[i] = sorted[i].second;
    }
  }
}

// ---- the overlap check's fast path ----------------------------------------
//
// Once facet_pass has passed (every facet in one or two cells, the two on
// opposite sides), the cells form a chain whose boundary is the boundary
// facets: the number of cells holding a point y (off every facet) is the
// winding number of the boundary around y. A ray from y counts it: each
// boundary facet it passes through adds 1 where the ray leaves that facet's
// cell and takes 1 where it enters it. find_overlap fails only where the
// centroid of some cell lies inside another cell, where that number is at
// least 2. So when the ray from every centroid counts exactly 1, find_overlap
// would find nothing and need not run: it runs (and names the pair) only when
// some count is not 1, or some ray passes too near an edge of a facet, or
// starts too near one, for its count to be sure. The verdict and the message
// are find_overlap's in every case.
//
// The rays all go one way, r = (1, kSlope...), skew to every axis so that no
// facet of an axis-aligned box is parallel to them. In sheared coordinates
// z = (t, u), t = x_0 and u_k = x_{k+1} - kSlope[k] x_0, the ray from y keeps
// u(y) and runs up t. A facet with vertices z_0..z_{D-1} is met where u(y)
// lies in the facet's projection: with w_j = u(z_j) - u(y), the numbers
// D_i = (-1)^i det(w_j, j != i) all have one sign (they are the barycentric
// coordinates of u(y), times sum D_i), and the meeting point is ahead of y
// when sum_i D_i (t_i - t(y)) has that sign too. Just before it the ray is on
// the side (-1)^D sign(sum D) of O(x) = det(z_1 - z_0, ..., x - z_0), so it
// leaves the facet's cell when that is the side of the cell's other vertex.
// A determinant within kSure of its largest possible size (the sum of its
// terms' sizes, or the product of its columns' lengths), plus what rounding
// the coordinates can change, is not sure.
//
// Most rays need not be cast: where a box of a grid over the mesh meets no
// boundary facet, the count is the same all over it and over the boxes
// joined to it through such boxes, so one sure count serves all of them.
constexpr double kSlope[3] = {0.2971832417, 0.1852213817, 0.1127915737};
constexpr double kSure = 1e-11;

// det of the K x K matrix with columns a[0..K-1] (each K values; the
// transpose's, geometry::determinant's rows, is the same).
template <int K> double det_columns(const double (*a)[4]) {
  if constexpr (K == 1) {
    return a[0][0];
  } else {
    std::array<double, K * K> m;
    for (int j = 0; j < K; ++j)
      for (int r = 0; r < K; ++r)
        m[std::size_t(j * K + r)] = a[j][r];
    return geometry::determinant<K>(m);
  }
}

template <int K> double column_length(const double *a) {
  double s = 0;
  for (int k = 0; k < K; ++k)
    s += a[k] * a[k];
  return std::sqrt(s);
}

template <int Dim> void shear(const double *x, double *z) {
  z[0] = x[0];
  for (int k = 0; k + 1 < Dim; ++k)
    z[k + 1] = x[k + 1] - kSlope[k] * x[0];
}

// What centroids_wound_once learnt: the boxes of its grid, and which of them
// surely have count 1 all over (no boundary facet meets them, and a sure ray
// from a centroid in their region counted 1).
template <int Dim> struct WoundBoxes {
  double lo[Dim], size[Dim];
  std::int64_t n[Dim];
  std::vector<std::uint8_t> one; // per box

  // Whether the count is surely 1 at x and all around it.
  bool one_at(const double *x) const {
    std::size_t g = 0;
    for (int k = Dim - 1; k >= 0; --k) {
      const double t = (x[k] - lo[k]) / size[k];
      if (!(t >= 0 && t < double(n[k])))
        return false;
      g = g * std::size_t(n[k]) + std::size_t(grid_cell(t, n[k]));
    }
    return one[g] != 0;
  }
};

template <int Dim>
bool centroids_wound_once(const Mesh &mesh, const std::vector<VertexId> &bnd,
                          const std::vector<VertexId> &opposite,
                          WoundBoxes<Dim> *boxes_out = nullptr) {
  constexpr int U = Dim - 1, N = Dim + 1;
  g_overlap_fast_path_taken = false;
  const std::size_t nb = bnd.size() / Dim, nc = mesh.num_cells();
  if (nb == 0 || nc == 0 || opposite.size() != nb)
    return false;
  const int workers = int(std::clamp<std::size_t>(nc >> 15, 1, std::size_t(threads())));

  // Per facet: t of its sheared vertices, u of the first, the box of their
  // u, the side of O on which its cell lies (0: not sure) and each D_i as an
  // affine function of the offset v = u(y) - u(z_0): D_i = coef_i0 +
  // sum_k coef_i(k+1) v_k, exact in exact arithmetic (det is linear in each
  // column, and v appears in every column once).
  std::vector<double> ft(nb * Dim), fu(nb * U), fbox(nb * 2 * U), coef(nb * Dim * Dim);
  std::vector<std::int8_t> side(nb);
  double umax = 0, tmax = 0; // the largest |u| and |t|, for the rounding of differences
#pragma omp parallel for num_threads(workers) schedule(static) reduction(max : umax, tmax)
  for (std::size_t f = 0; f < nb; ++f) {
    double z[Dim][Dim];
    for (int j = 0; j < Dim; ++j)
      shear<Dim>(mesh.point(bnd[f * Dim + std::size_t(j)]), z[j]);
    double *box = &fbox[f * 2 * U];
    double scale = 0;
    for (int k = 0; k < U; ++k) {
      fu[f * U + std::size_t(k)] = z[0][k + 1];
      box[k] = box[U + k] = z[0][k + 1];
      for (int j = 1; j < Dim; ++j) {
        box[k] = std::min(box[k], z[j][k + 1]);
        box[U + k] = std::max(box[U + k], z[j][k + 1]);
      }
      scale = std::max(scale, box[U + k] - box[k]);
      umax = std::max({umax, std::abs(box[k]), std::abs(box[U + k])});
    }
    for (int j = 0; j < Dim; ++j) {
      ft[f * Dim + std::size_t(j)] = z[j][0];
      tmax = std::max(tmax, std::abs(z[j][0]));
    }
    // D_i at v = 0 and at v = scale e_k.
    auto d_at = [&](int i, int k) {
      double cols[4][4];
      for (int j = 0, c = 0; j < Dim; ++j)
        if (j != i) {
          for (int m = 0; m < U; ++m)
            cols[c][m] = z[j][m + 1] - z[0][m + 1] - (m == k ? scale : 0.0);
          ++c;
        }
      return (i % 2 ? -1.0 : 1.0) * det_columns<U>(cols);
    };
    for (int i = 0; i < Dim; ++i) {
      double *ci = &coef[(f * Dim + std::size_t(i)) * Dim];
      ci[0] = d_at(i, -1);
      for (int k = 0; k < U; ++k)
        ci[k + 1] = scale > 0 ? (d_at(i, k) - ci[0]) / scale : 0.0;
    }
    double q[Dim], cols[4][4];
    shear<Dim>(mesh.point(opposite[f]), q);
    double bound = 1;
    for (int j = 0; j < Dim; ++j) {
      for (int k = 0; k < Dim; ++k)
        cols[j][k] = (j + 1 < Dim ? z[j + 1][k] : q[k]) - z[0][k];
      bound *= column_length<Dim>(cols[j]);
    }
    const double o = det_columns<Dim>(cols);
    side[f] = std::int8_t(o > kSure * bound ? 1 : o < -kSure * bound ? -1 : 0);
  }
  // The rounding of v: a few units in the last place of the largest |u|.
  const double vround = 8 * std::numeric_limits<double>::epsilon() * umax;
  const double tround = 8 * std::numeric_limits<double>::epsilon() * tmax;

  // A grid over u: about two cells per facet, each facet listed in the
  // cells its box covers.
  double lo[U], hi[U];
  std::fill(lo, lo + U, 1e300);
  std::fill(hi, hi + U, -1e300);
  for (std::size_t f = 0; f < nb; ++f)
    for (int k = 0; k < U; ++k) {
      lo[k] = std::min(lo[k], fbox[f * 2 * U + std::size_t(k)]);
      hi[k] = std::max(hi[k], fbox[f * 2 * U + std::size_t(U + k)]);
    }
  double volume = 1;
  int spread = 0;
  for (int k = 0; k < U; ++k)
    if (hi[k] > lo[k]) {
      volume *= hi[k] - lo[k];
      ++spread;
    }
  if (!(std::isfinite(volume)) || spread < U)
    return false; // a flat or infinite projection: leave it to find_overlap
  const double side_length = std::pow(volume / (2.0 * double(nb)), 1.0 / U);
  std::int64_t cells[U];
  double size[U];
  std::size_t total = 1;
  for (int k = 0; k < U; ++k) {
    cells[k] = std::clamp<std::int64_t>(std::int64_t((hi[k] - lo[k]) / side_length) + 1, 1, 4096);
    size[k] = (hi[k] - lo[k]) / double(cells[k]);
    total *= std::size_t(cells[k]);
  }
  auto index = [&](double x, int k) { return grid_cell((x - lo[k]) / size[k], cells[k]); };
  std::vector<std::uint32_t> start(total + 1, 0);
  auto each_cell = [&](std::size_t f, auto &&visit) {
    const double *box = &fbox[f * 2 * U];
    std::int64_t a[U], b[U];
    for (int k = 0; k < U; ++k) {
      a[k] = index(box[k], k);
      b[k] = index(box[U + k], k);
    }
    for_each_box<U>(a, b, [&](const std::int64_t *at) {
      visit(box_number<U>(at, cells));
      return true;
    });
  };
  std::size_t entries = 0;
  for (std::size_t f = 0; f < nb; ++f)
    each_cell(f, [&](std::size_t g) { ++start[g + 1], ++entries; });
  if (entries > 64 * nb + (std::size_t(1) << 20))
    return false; // facets far larger than the grid's cells: not worth it
  for (std::size_t g = 0; g < total; ++g)
    start[g + 1] += start[g];
  std::vector<std::uint32_t> listed(entries);
  {
    std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < nb; ++f)
      each_cell(f, [&](std::size_t g) { listed[at[g]++] = std::uint32_t(f); });
  }

  // What facet f adds to the count along the ray from y (sheared): +1, -1
  // or 0, kUnsure when not sure. D_i is sure when it exceeds kSure times the
  // sum of its terms' sizes plus what the rounding of v can change.
  constexpr int kUnsure = std::numeric_limits<int>::min();
  auto cross = [&](std::size_t f, const double *y) {
    const double *box = &fbox[f * 2 * U];
    bool in = true;
    for (int k = 0; k < U; ++k)
      in &= (y[k + 1] >= box[k]) & (y[k + 1] <= box[U + k]);
    if (!in)
      return 0;
    double v[U];
    for (int k = 0; k < U; ++k)
      v[k] = y[k + 1] - fu[f * U + std::size_t(k)];
    double d[Dim], sum = 0;
    bool positive = false, negative = false, unsure = false;
    for (int i = 0; i < Dim; ++i) {
      const double *ci = &coef[(f * Dim + std::size_t(i)) * Dim];
      double value = ci[0], size = std::abs(ci[0]), slope = 0;
      for (int k = 0; k < U; ++k) {
        value += ci[k + 1] * v[k];
        size += std::abs(ci[k + 1] * v[k]);
        slope += std::abs(ci[k + 1]);
      }
      const double margin = kSure * size + slope * vround;
      d[i] = value;
      sum += value;
      positive |= value > margin;
      negative |= value < -margin;
      unsure |= !(std::abs(value) > margin);
      if (positive && negative)
        return 0; // surely outside the projection
    }
    if (unsure || side[f] == 0)
      return kUnsure;
    // Ahead of y: the sign of sum_i d_i (t_i - t(y)) is that of sum d.
    double ahead = 0, bound = 0, weight = 0;
    for (int i = 0; i < Dim; ++i) {
      const double dt = ft[f * Dim + std::size_t(i)] - y[0];
      ahead += d[i] * dt;
      bound += std::abs(d[i] * dt);
      weight += std::abs(d[i]);
    }
    if (!(std::abs(ahead) > kSure * bound + weight * tround))
      return kUnsure;
    if ((ahead > 0) != (sum > 0))
      return 0; // behind y
    const int before = (Dim % 2 ? -1 : 1) * (sum > 0 ? 1 : -1);
    return before == side[f] ? 1 : -1;
  };
  auto winding = [&](const double *y) {
    int count = 0;
    std::size_t g = 0;
    for (int k = U - 1; k >= 0; --k) {
      if (!(y[k + 1] >= lo[k] && y[k + 1] <= hi[k]))
        return 0; // no facet around
      g = g * std::size_t(cells[k]) + std::size_t(index(y[k + 1], k));
    }
    for (std::uint32_t e = start[g]; e < start[g + 1]; ++e) {
      const int c = cross(listed[e], y);
      if (c == kUnsure)
        return kUnsure;
      count += c;
    }
    return count;
  };

  // Boxes of a grid over the mesh (about one per 4 cells) that no boundary
  // facet's box meets: the count is the same everywhere in such a box, and
  // in face-adjacent ones (their union is connected and meets no boundary
  // facet), so each connected region of them takes its count from the
  // first centroid in it whose own count is sure; a centroid in a box a
  // facet meets counts its own.
  double glo[Dim], ghi[Dim];
  std::fill(glo, glo + Dim, 1e300);
  std::fill(ghi, ghi + Dim, -1e300);
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < Dim; ++k) {
      glo[k] = std::min(glo[k], mesh.point(VertexId(v))[k]);
      ghi[k] = std::max(ghi[k], mesh.point(VertexId(v))[k]);
    }
  double gvolume = 1, reach = 0;
  for (int k = 0; k < Dim; ++k) {
    gvolume *= ghi[k] - glo[k];
    reach = std::max({reach, std::abs(glo[k]), std::abs(ghi[k])});
  }
  if (!(gvolume > 0) || !std::isfinite(gvolume))
    return false;
  const double gside = std::pow(gvolume / std::max(1.0, double(nc) / 4), 1.0 / Dim);
  std::int64_t gn[Dim];
  double gsize[Dim];
  std::size_t boxes = 1;
  for (int k = 0; k < Dim; ++k) {
    gn[k] = std::clamp<std::int64_t>(std::int64_t((ghi[k] - glo[k]) / gside) + 1, 1, 1 << 14);
    gsize[k] = (ghi[k] - glo[k]) / double(gn[k]);
    boxes *= std::size_t(gn[k]);
  }
  if (boxes > 4 * nc + 1024)
    return false;
  auto gindex = [&](double x, int k) { return grid_cell((x - glo[k]) / gsize[k], gn[k]); };
  // Marked: a facet's box, widened by far more than rounding, meets it.
  constexpr std::uint32_t kMet = ~std::uint32_t(0);
  std::vector<std::uint32_t> region(boxes, 0);
  {
    const double widen = 1e-9 * reach;
    std::size_t marks = 0;
    for (std::size_t f = 0; f < nb; ++f) {
      std::int64_t a[Dim], b[Dim];
      for (int k = 0; k < Dim; ++k) {
        double l = 1e300, h = -1e300;
        for (int j = 0; j < Dim; ++j) {
          const double x = mesh.point(bnd[f * Dim + std::size_t(j)])[k];
          l = std::min(l, x);
          h = std::max(h, x);
        }
        a[k] = gindex(l - widen, k);
        b[k] = gindex(h + widen, k);
      }
      bool fits = true;
      for_each_box<Dim>(a, b, [&](const std::int64_t *at) {
        region[box_number<Dim>(at, gn)] = kMet;
        return fits = ++marks <= (std::size_t(64) << 20);
      });
      if (!fits)
        return false; // facets far larger than the boxes: not worth it
    }
  }
  // The regions: numbered from 1 by a flood over face neighbours.
  std::uint32_t regions = 0;
  {
    std::vector<std::size_t> stride(Dim), queue;
    for (int k = 0; k < Dim; ++k)
      stride[std::size_t(k)] = k == 0 ? 1 : stride[std::size_t(k - 1)] * std::size_t(gn[k - 1]);
    for (std::size_t g0 = 0; g0 < boxes; ++g0) {
      if (region[g0] != 0)
        continue;
      region[g0] = ++regions;
      queue.assign(1, g0);
      while (!queue.empty()) {
        const std::size_t g = queue.back();
        queue.pop_back();
        for (int k = 0; k < Dim; ++k) {
          const std::size_t i = g / stride[std::size_t(k)] % std::size_t(gn[k]);
          if (i > 0 && region[g - stride[std::size_t(k)]] == 0) {
            region[g - stride[std::size_t(k)]] = regions;
            queue.push_back(g - stride[std::size_t(k)]);
          }
          if (i + 1 < std::size_t(gn[k]) && region[g + stride[std::size_t(k)]] == 0) {
            region[g + stride[std::size_t(k)]] = regions;
            queue.push_back(g + stride[std::size_t(k)]);
          }
        }
      }
    }
  }
  // Per region: its count once known (kUnknown before).
  constexpr int kUnknown = std::numeric_limits<int>::max();
  std::vector<std::atomic<int>> count_of(std::size_t(regions) + 1);
  for (auto &c : count_of)
    c.store(kUnknown, std::memory_order_relaxed);

  constexpr std::size_t kBlock = std::size_t(1) << 13;
  const std::size_t blocks = (nc + kBlock - 1) / kBlock;
  std::atomic<bool> sure{true};
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t b = 0; b < blocks; ++b) {
    if (!sure.load(std::memory_order_relaxed))
      continue;
    double pts[N * Dim];
    for (std::size_t c = b * kBlock; c < std::min(nc, (b + 1) * kBlock); ++c) {
      gather<Dim>(mesh, mesh.cell(CellId(c)), N, pts);
      double x[Dim], y[Dim];
      for (int k = 0; k < Dim; ++k) {
        double sum = 0;
        for (int i = 0; i < N; ++i)
          sum += pts[i * Dim + k];
        x[k] = sum / N;
      }
      std::size_t g = 0;
      for (int k = Dim - 1; k >= 0; --k)
        g = g * std::size_t(gn[k]) + std::size_t(gindex(x[k], k));
      const std::uint32_t r = region[g];
      int count = r == kMet ? kUnknown : count_of[r].load(std::memory_order_relaxed);
      if (count == kUnknown) {
        shear<Dim>(x, y);
        count = winding(y);
        if (r != kMet && count != kUnsure)
          count_of[r].store(count, std::memory_order_relaxed);
      }
      if (count != 1) {
        sure = false;
        break;
      }
    }
  }
  g_overlap_fast_path_taken = sure;
  if (sure && boxes_out) {
    std::copy(glo, glo + Dim, boxes_out->lo);
    std::copy(gsize, gsize + Dim, boxes_out->size);
    std::copy(gn, gn + Dim, boxes_out->n);
    boxes_out->one.assign(boxes, 0);
    for (std::size_t g = 0; g < boxes; ++g)
      boxes_out->one[g] =
          region[g] != kMet && count_of[region[g]].load(std::memory_order_relaxed) == 1;
  }
  return sure;
}

template <int Dim> std::string find_overlap(const Mesh &mesh) {
  constexpr int N = Dim + 1;
  using Z = ZOrder<Dim>;
  using Key = typename Z::Key;
  const std::size_t nc = mesh.num_cells();
  if (nc < 2)
    return {};
  // Blocks of cells fixed by the mesh; sums and findings are combined in
  // block order.
  constexpr std::size_t kBlock = std::size_t(1) << 13;
  const std::size_t blocks = (nc + kBlock - 1) / kBlock;
  const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));

  // The centroids, the bounding box of the cells and their mean extent.
  std::vector<double, UninitialisedAllocator<double>> centroid(nc * Dim);
  std::vector<std::array<double, 2 * Dim + 1>> block_box(blocks); // lo, hi, sum of extents
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t k = 0; k < blocks; ++k) {
    double pts[N * Dim];
    auto &box = block_box[k];
    std::fill(box.begin(), box.begin() + Dim, 1e300);
    std::fill(box.begin() + Dim, box.begin() + 2 * Dim, -1e300);
    double h = 0;
    for (std::size_t c = k * kBlock; c < std::min(nc, (k + 1) * kBlock); ++c) {
      gather<Dim>(mesh, mesh.cell(CellId(c)), N, pts);
      double ext = 0;
      for (int d = 0; d < Dim; ++d) {
        double a = pts[d], b = pts[d], sum = 0;
        for (int i = 0; i < N; ++i) {
          a = std::min(a, pts[i * Dim + d]);
          b = std::max(b, pts[i * Dim + d]);
          sum += pts[i * Dim + d];
        }
        centroid[c * Dim + d] = sum / N;
        box[d] = std::min(box[d], a);
        box[Dim + d] = std::max(box[Dim + d], b);
        ext = std::max(ext, b - a);
      }
      h += ext;
    }
    box[2 * Dim] = h;
  }
  double lo[Dim], hi[Dim], h = 0;
  std::fill(lo, lo + Dim, 1e300);
  std::fill(hi, hi + Dim, -1e300);
  for (const auto &box : block_box) {
    for (int d = 0; d < Dim; ++d) {
      lo[d] = std::min(lo[d], box[d]);
      hi[d] = std::max(hi[d], box[Dim + d]);
    }
    h += box[2 * Dim];
  }
  h /= double(nc);
  if (!(h > 0))
    return {};

  // The skip rule's grid: half the mean extent.
  constexpr int kGridBits = 64 / Dim;
  std::int64_t ncell[Dim];
  double size[Dim];
  for (int d = 0; d < Dim; ++d) {
    size[d] = std::max(h / 2, (hi[d] - lo[d]) / double((std::uint64_t(1) << (kGridBits - 1)) - 1));
    ncell[d] = std::int64_t((hi[d] - lo[d]) / size[d]) + 1;
  }
  auto grid_index = [&](double x, int d) { return grid_cell((x - lo[d]) / size[d], ncell[d]); };

  // Quantization for the keys: monotone in each coordinate, so a point in a
  // box quantizes into the quantized box.
  const Z z;
  double scale[Dim];
  const double top = double((std::uint64_t(1) << Z::kBits) - 1);
  for (int d = 0; d < Dim; ++d)
    scale[d] = hi[d] > lo[d] ? top / (hi[d] - lo[d]) : 0.0;
  auto quantize = [&](const double *x, std::uint32_t *q) {
    for (int d = 0; d < Dim; ++d)
      q[d] = std::uint32_t(grid_cell((x[d] - lo[d]) * scale[d], std::int64_t(top) + 1));
  };

  // The centroids in key order.
  std::vector<Key> keys(nc);
  std::vector<CellId> ids(nc);
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t k = 0; k < blocks; ++k)
    for (std::size_t c = k * kBlock; c < std::min(nc, (k + 1) * kBlock); ++c) {
      std::uint32_t q[Dim];
      quantize(&centroid[c * Dim], q);
      keys[c] = z.key(q);
      ids[c] = CellId(c);
    }
  sort_by_key(keys, ids, Z::kKeyBits);
  std::vector<double, UninitialisedAllocator<double>> ordered(nc * Dim);
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t k = 0; k < blocks; ++k)
    for (std::size_t i = k * kBlock; i < std::min(nc, (k + 1) * kBlock); ++i)
      std::copy_n(&centroid[std::size_t(ids[i]) * Dim], Dim, &ordered[i * Dim]);
  decltype(centroid)().swap(centroid);

  // Groups of cells: the leaves of an octree over the sorted keys, each the
  // centroids of one aligned Z cell (a box), at most kGroup of them (more
  // only where keys are equal). A group's cells query together: the
  // centroids in the union of their boxes are found by one range search
  // and put in a small grid of the group's own mean extent, which each
  // cell's box then reads (no range search per cell).
  constexpr std::size_t kGroup = 2048;
  constexpr double kPerCell = 2, kMargin = 1;
  std::vector<std::array<std::size_t, 2>> groups;
  {
    std::vector<std::array<std::size_t, 3>> stack{{0, nc, std::size_t(Z::kKeyBits)}};
    while (!stack.empty()) {
      const auto [from, to, bits] = stack.back(); // keys in [from, to) agree above `bits`
      stack.pop_back();
      if (to - from <= kGroup || bits == 0) {
        groups.push_back({from, to});
        continue;
      }
      const Key bit = Key(1) << (bits - 1);
      const std::size_t mid = std::size_t(std::partition_point(keys.begin() + std::ptrdiff_t(from),
                                                               keys.begin() + std::ptrdiff_t(to),
                                                               [&](Key k) { return !(k & bit); }) -
                                          keys.begin());
      if (mid < to)
        stack.push_back({mid, to, bits - 1}); // popped after the lower half
      if (from < mid)
        stack.push_back({from, mid, bits - 1});
    }
  }

  // The sorted positions j of keys in the box of corner keys zlo <= zhi,
  // appended to `out`: keys in chunks of kRun, tested without branches; a
  // chunk with none in the box is a run outside it, jumped over with BIGMIN.
  auto range_search = [&](Key zlo, Key zhi, std::vector<std::uint32_t> &out) {
    constexpr std::size_t kRun = 16;
    std::size_t at = std::size_t(std::lower_bound(keys.begin(), keys.end(), zlo) - keys.begin());
    while (at < nc) {
      const std::size_t end = std::min(nc, at + kRun);
      std::size_t hits = out.size();
      out.resize(hits + kRun);
      for (std::size_t j = at; j < end; ++j) {
        out[hits] = std::uint32_t(j);
        hits += z.inside(keys[j], zlo, zhi);
      }
      const bool any = hits != out.size() - kRun;
      out.resize(hits);
      const Key last = keys[end - 1];
      at = end;
      if (last > zhi)
        break;
      if (any)
        continue;
      const Key next = z.next_inside(last, zlo, zhi);
      if (next == ~Key(0) || next > zhi)
        break;
      std::size_t from = at, span = 1;
      while (from + span < nc && keys[from + span] < next)
        from += span, span *= 2;
      at = std::size_t(
          std::lower_bound(keys.begin() + std::ptrdiff_t(from),
                           keys.begin() + std::ptrdiff_t(std::min(nc, from + span + 1)), next) -
          keys.begin());
    }
  };

  // Each group: its smallest (cell, other cell) finding.
  constexpr std::uint64_t kNone = ~std::uint64_t(0);
  const std::size_t ngroups = groups.size();
  std::vector<std::uint64_t> found(ngroups, kNone);
  const int group_workers = int(std::clamp<std::size_t>(nc >> 15, 1, std::size_t(threads())));
#pragma omp parallel num_threads(group_workers)
  {
    std::vector<double> qpts, qbox;   // the group's cells: points, boxes
    std::vector<std::uint8_t> skip;   // a huge cell, not queried
    std::vector<std::uint32_t> near;  // sorted positions of centroids in the union box
    std::vector<std::uint32_t> start; // the small grid: bucket starts,
    std::vector<std::uint32_t> slot;  // bucket of each of `near`,
    std::vector<double> bx;           // and the centroids bucket by bucket
    std::vector<CellId> bid;          // with their cells
    std::vector<std::uint32_t> mine;  // a cell's own search
    std::vector<std::uint32_t> hit;   // the centroids in a cell's box
#pragma omp for schedule(dynamic, 8)
    for (std::size_t g = 0; g < ngroups; ++g) {
      const std::size_t from = groups[g][0], to = groups[g][1], count = to - from;
      qpts.resize(count * N * Dim);
      qbox.resize(count * 2 * Dim);
      skip.assign(count, 0);
      double ulo[Dim], uhi[Dim], extent = 0;
      std::fill(ulo, ulo + Dim, 1e300);
      std::fill(uhi, uhi + Dim, -1e300);
      std::size_t queried = 0;
      for (std::size_t q = 0; q < count; ++q) {
        const std::size_t i = from + q;
        // The cells ahead in key order are far apart in the file: fetch
        // their vertex ids, then their vertices, before they are needed.
        if (i + 16 < nc)
          __builtin_prefetch(mesh.cell(ids[i + 16]));
        if (i + 8 < nc)
          for (int j = 0; j < N; ++j)
            __builtin_prefetch(mesh.point(mesh.cell(ids[i + 8])[j]));
        double *pts = &qpts[q * N * Dim], *box = &qbox[q * 2 * Dim];
        gather<Dim>(mesh, mesh.cell(ids[i]), N, pts);
        double cover = 1, ext = 0;
        for (int d = 0; d < Dim; ++d) {
          double a = pts[d], b = pts[d];
          for (int j = 1; j < N; ++j)
            a = std::min(a, pts[j * Dim + d]), b = std::max(b, pts[j * Dim + d]);
          box[d] = a;
          box[Dim + d] = b;
          ext = std::max(ext, b - a);
          cover *= double(grid_index(b, d) - grid_index(a, d) + 1);
        }
        if (cover > (4096 << Dim)) {
          skip[q] = 1; // a huge cell among small ones: skipped, not worth the search
          continue;
        }
        for (int d = 0; d < Dim; ++d) {
          ulo[d] = std::min(ulo[d], box[d]);
          uhi[d] = std::max(uhi[d], box[Dim + d]);
        }
        extent += ext;
        ++queried;
      }
      if (queried == 0)
        continue;
      extent /= double(queried);
      // The grid's box: the group's centroids' box widened by kMargin mean
      // extents, within the union of the boxes. A cell whose box passes it
      // (a large one near the group's edge) searches on its own.
      for (int d = 0; d < Dim; ++d) {
        double a = 1e300, b = -1e300;
        for (std::size_t i = from; i < to; ++i)
          a = std::min(a, ordered[i * Dim + std::size_t(d)]),
          b = std::max(b, ordered[i * Dim + std::size_t(d)]);
        ulo[d] = std::max(ulo[d], a - kMargin * extent);
        uhi[d] = std::min(uhi[d], b + kMargin * extent);
      }
      // The centroids in it.
      std::uint32_t qlo[Dim], qhi[Dim];
      quantize(ulo, qlo);
      quantize(uhi, qhi);
      near.clear();
      range_search(z.key(qlo), z.key(qhi), near);
      // The small grid over the union box: about kPerCell centroids a cell
      // (cubes of the volume that holds them, on average).
      double cell[Dim];
      std::int64_t cells[Dim];
      std::size_t total = 1;
      {
        double volume = 1;
        int flat = 0;
        for (int d = 0; d < Dim; ++d) {
          if (uhi[d] > ulo[d])
            volume *= uhi[d] - ulo[d];
          else
            ++flat;
        }
        const double side =
            flat ? extent : std::pow(volume * kPerCell / double(near.size() + 1), 1.0 / Dim);
        for (int d = 0; d < Dim; ++d) {
          cell[d] = std::max({side, extent / 8, 1e-300});
          cells[d] = std::int64_t(std::min(1024.0, (uhi[d] - ulo[d]) / cell[d])) + 1;
          total *= std::size_t(cells[d]);
        }
      }
      auto index = [&](double x, int d) { return grid_cell((x - ulo[d]) / cell[d], cells[d]); };
      start.assign(total + 1, 0);
      slot.resize(near.size());
      for (std::size_t k = 0; k < near.size(); ++k) {
        const double *x = &ordered[std::size_t(near[k]) * Dim];
        std::size_t s = 0;
        for (int d = Dim - 1; d >= 0; --d)
          s = s * std::size_t(cells[d]) + std::size_t(index(x[d], d));
        slot[k] = std::uint32_t(s);
        ++start[s + 1];
      }
      for (std::size_t s = 0; s < total; ++s)
        start[s + 1] += start[s];
      bx.resize(near.size() * Dim);
      bid.resize(near.size());
      hit.resize(near.size() + 1);
      for (std::size_t k = 0; k < near.size(); ++k) {
        const std::uint32_t at = start[slot[k]]++;
        std::copy_n(&ordered[std::size_t(near[k]) * Dim], Dim, &bx[std::size_t(at) * Dim]);
        bid[at] = ids[near[k]];
      }
      for (std::size_t s = total; s > 0; --s) // back to the starts
        start[s] = start[s - 1];
      start[0] = 0;

      std::uint64_t best = kNone;
      for (std::size_t q = 0; q < count; ++q) {
        const CellId c = ids[from + q];
        if (skip[q] || (best != kNone && c > CellId(best >> 32)))
          continue; // skipped, or cannot beat this group's finding
        const double *pts = &qpts[q * N * Dim], *box = &qbox[q * 2 * Dim];
        double inv[Dim * Dim];
        // Barycentric coordinates in the cell: lambda[1..Dim] = inv (x - p0),
        // with inv the inverse of the edge matrix (columns p_j - p0), made
        // once per cell when a centroid first falls in its box; lambda[0] =
        // 1 - the rest.
        auto make_inverse = [&]() {
          double gm[Dim * Dim];
          for (int r = 0; r < Dim; ++r)
            for (int e = 0; e < Dim; ++e)
              gm[r * Dim + e] = pts[(e + 1) * Dim + r] - pts[r];
          double identity[Dim * Dim];
          for (int r = 0; r < Dim; ++r)
            for (int e = 0; e < Dim; ++e)
              identity[r * Dim + e] = r == e ? 1.0 : 0.0;
          return small_solve(gm, identity, Dim, inv, Dim);
        };
        int inv_state = 0; // 0 not made yet, 1 made, -1 the cell is singular
        CellId other = CellId(-1);
        // Centroid x of cell o, in the cell's box: inside the cell (and a
        // smaller finding)?
        auto test = [&](const double *x, CellId o) {
          if (o == c || o >= other)
            return;
          if (inv_state == 0)
            inv_state = make_inverse() ? 1 : -1;
          bool inside = inv_state == 1; // nothing is inside a singular cell
          double rest = 1;
          for (int j2 = 0; j2 < Dim && inside; ++j2) {
            double lambda = 0;
            for (int e = 0; e < Dim; ++e)
              lambda += inv[j2 * Dim + e] * (x[e] - pts[e]);
            rest -= lambda;
            inside = lambda > 1e-9;
          }
          if (inside && rest > 1e-9)
            other = o;
        };
        // Whether x lies in the cell's box (without branches: the outcome
        // is hard to predict).
        auto in_box = [&](const double *x) {
          bool in = true;
          for (int d = 0; d < Dim; ++d)
            in &= (x[d] >= box[d]) & (x[d] <= box[Dim + d]);
          return in;
        };
        bool within = !g_own_overlap_search;
        for (int d = 0; d < Dim; ++d)
          within &= box[d] >= ulo[d] && box[Dim + d] <= uhi[d];
        if (!within) { // its own search
          std::uint32_t blo[Dim], bhi[Dim];
          quantize(box, blo);
          quantize(box + Dim, bhi);
          mine.clear();
          range_search(z.key(blo), z.key(bhi), mine);
          for (const std::uint32_t j : mine)
            if (in_box(&ordered[std::size_t(j) * Dim]))
              test(&ordered[std::size_t(j) * Dim], ids[j]);
        } else {
          std::int64_t lo_i[Dim], hi_i[Dim], at_i[Dim];
          for (int d = 0; d < Dim; ++d) {
            lo_i[d] = at_i[d] = index(box[d], d);
            hi_i[d] = index(box[Dim + d], d);
          }
          // The centroids in the box: every row of small-grid cells the box
          // covers (along the first coordinate, whose cells are one run of
          // the buckets), the hits written down without branches.
          std::size_t hits = 0;
          while (true) {
            std::size_t s = 0;
            for (int d = Dim - 1; d > 0; --d)
              s = s * std::size_t(cells[d]) + std::size_t(at_i[d]);
            s *= std::size_t(cells[0]);
            const std::uint32_t end = start[s + std::size_t(hi_i[0]) + 1];
            for (std::uint32_t k = start[s + std::size_t(lo_i[0])]; k < end; ++k) {
              hit[hits] = k;
              hits += in_box(&bx[std::size_t(k) * Dim]);
            }
            int d = 1;
            while (d < Dim && at_i[d] == hi_i[d])
              at_i[d] = lo_i[d], ++d;
            if (d == Dim)
              break;
            ++at_i[d];
          }
          for (std::size_t h = 0; h < hits; ++h)
            test(&bx[std::size_t(hit[h]) * Dim], bid[hit[h]]);
        }
        if (other != CellId(-1))
          best = std::min(best, std::uint64_t(c) << 32 | other);
      }
      found[g] = best;
    }
  }
  const std::uint64_t best = *std::min_element(found.begin(), found.end());
  if (best == kNone)
    return {};
  const CellId c = CellId(best >> 32), o = CellId(best & 0xFFFFFFFFu);
  return cell_pair_name(mesh, c, o) + " overlap (the centroid of " + cell_name(mesh, o) +
         " lies inside " + cell_name(mesh, c) + ")";
}

// Local injectivity (the angle condition): around every codimension-2 face
// F (a vertex in 2D, an edge in 3D, a triangle in 4D) the dihedral angles at
// F of the cells containing it sum to 2π when F is interior, and to the
// interior angle of the boundary at F when F lies in exactly two boundary
// facets. Everything happens in the plane normal to F: each cell is a wedge
// between the projections u_a, u_b of its two vertices off F, of angle in
// (0, π). Once every interior facet has its two cells on opposite sides
// (facet_pass), consecutive wedges turn the same way, so the sum exceeds the
// expected value by a whole number of turns: 2π·k, k >= 0, and k > 0 exactly
// when the cells fold over each other there. Hence the threshold π: exact
// in exact arithmetic and blind to rounding, even in accepted slivers.
// A face in more boundary facets (a pinch) has several fans of cells, each
// checked against the boundary angle between its two end facets, and
// together they must not exceed one turn.
struct AngleFinding {
  double sum = 0, expected = 0;
  int cells = 0;
  bool boundary = false;
};

// atan2(y, x) for y >= 0 within 2e-5 (the polynomial for atan on [0, 1]
// of Abramowitz and Stegun, 4.4.49); NaN where atan2 would be exact-zero
// degenerate (0, 0), which fails the caller's test and takes atan2.
double rough_angle(std::pair<double, double> yx) {
  const double y = yx.first, ax = std::abs(yx.second);
  const bool steep = y > ax;
  const double t = steep ? ax / y : y / ax, t2 = t * t;
  double a =
      t * (0.9998660 + t2 * (-0.3302995 + t2 * (0.1801410 + t2 * (-0.0851330 + t2 * 0.0208351))));
  if (steep)
    a = M_PI / 2 - a;
  return yx.second < 0 ? M_PI - a : a;
}

template <int Dim> class StarAngles {
public:
  explicit StarAngles(const Mesh &mesh) : mesh_(&mesh) {}

  // face: Dim - 1 vertex ids; extras[2 i], extras[2 i + 1]: the other two
  // vertices of cell i. True when the star of the face is tangled.
  bool tangled(const VertexId *face, const VertexId *extras, int n, AngleFinding &out) {
    constexpr int K = Dim - 1;
    const double *f0 = mesh_->point(face[0]);
    int nb = 0; // orthonormal basis of the span of F - f0
    for (int i = 1; i < K; ++i) {
      double e[Dim];
      for (int d = 0; d < Dim; ++d)
        e[d] = mesh_->point(face[i])[d] - f0[d];
      for (int j = 0; j < nb; ++j) {
        const double s = dot(e, basis_[j]);
        for (int d = 0; d < Dim; ++d)
          e[d] -= s * basis_[j][d];
      }
      const double len = std::sqrt(dot(e, e));
      if (!(len > 0))
        return false;
      for (int d = 0; d < Dim; ++d)
        basis_[nb][d] = e[d] / len;
      ++nb;
    }
    angle_.resize(n);
    wedge_.resize(std::size_t(n));
    double rough = 0;
    for (int i = 0; i < n; ++i) {
      double ua[Dim], ub[Dim];
      project(f0, nb, extras[2 * i], ua);
      project(f0, nb, extras[2 * i + 1], ub);
      wedge_[std::size_t(i)] = sides(ua, ub);
      rough += rough_angle(wedge_[std::size_t(i)]);
    }
    constexpr double kTwoPi = 2 * M_PI;
    out.cells = n;
    // An interior face, the common case: every vertex off F in two of the
    // cells, so the link is cycles only, and the sum must be one turn (what
    // the walk below finds for it, without its sort).
    bool twice = true;
    for (int a = 0; a < 2 * n && twice; ++a) {
      int same = 0;
      for (int b = 0; b < 2 * n; ++b)
        same += extras[a] == extras[b];
      twice = same == 2;
    }
    // The link's cycles turn a whole number of times; with the rough
    // angles (each within 2e-5 of atan2's) near one turn, the exact sum is
    // within pi of it too, and the face is fine: the exact angles below
    // (libm's atan2, about 5% of `bisect info`'s time before) are needed
    // only for the other faces.
    if (twice && n < 10000 && std::abs(rough - kTwoPi) < M_PI / 2)
      return false;
    double total = 0;
    for (int i = 0; i < n; ++i) {
      const auto [y, x] = wedge_[std::size_t(i)];
      angle_[i] = std::atan2(y, x);
      total += angle_[i];
    }
    {
      if (twice) {
        out.boundary = false;
        out.expected = kTwoPi;
        out.sum = total;
        return std::abs(total - kTwoPi) > M_PI;
      }
    }
    // The link of F: the vertices off F, joined by the cells. Each has one
    // or two cells (facet_pass), so the link is paths (their ends: boundary
    // facets) and cycles. entry_: (vertex, cell) sorted by vertex.
    entry_.clear();
    for (int i = 0; i < n; ++i) {
      entry_.push_back({extras[2 * i], i});
      entry_.push_back({extras[2 * i + 1], i});
    }
    std::sort(entry_.begin(), entry_.end());
    auto cells_of = [&](VertexId v) {
      auto first = std::lower_bound(entry_.begin(), entry_.end(), std::make_pair(v, 0));
      auto last = first;
      while (last != entry_.end() && last->first == v)
        ++last;
      return std::make_pair(first, last);
    };
    auto other = [&](int cell, VertexId v) {
      return extras[2 * cell] == v ? extras[2 * cell + 1] : extras[2 * cell];
    };
    seen_.assign(n, 0);
    fans_.clear();
    int paths = 0;
    for (std::size_t e = 0; e < entry_.size();) {
      auto [first, last] = cells_of(entry_[e].first);
      e = std::size_t(last - entry_.begin());
      if (last - first != 1 || seen_[first->second])
        continue;
      // A path from boundary facet F + p to boundary facet F + q.
      const VertexId p = first->first;
      int cell = first->second;
      const VertexId w = other(cell, p);
      VertexId at = p;
      double sum = 0;
      int cells = 0;
      for (;;) {
        seen_[cell] = 1;
        sum += angle_[cell];
        ++cells;
        at = other(cell, at);
        auto [f2, l2] = cells_of(at);
        if (l2 - f2 != 2)
          break;
        cell = f2->second == cell ? (f2 + 1)->second : f2->second;
      }
      ++paths;
      fans_.push_back({p, w, sum});
      out.sum = sum;
      out.cells = cells;
      out.boundary = true;
      if (!boundary_angle_fits(f0, nb, p, w, at, sum, out.expected))
        return true;
    }
    double cycles = 0;
    int in_cycles = 0;
    for (int i = 0; i < n; ++i)
      if (!seen_[i])
        cycles += angle_[i], ++in_cycles;
    out.boundary = false;
    out.expected = kTwoPi;
    if (in_cycles > 0 && (paths > 0 || std::abs(cycles - kTwoPi) > M_PI)) {
      out.sum = total;
      out.cells = n;
      return true; // more than one turn, or a turn and boundary fans besides
    }
    // Fans of a pinched face must not overlap one another: their angular
    // intervals in one frame (e1, e2) of the normal plane, sorted by start,
    // each end before the next start (within 1e-6 of a turn).
    if (paths > 1) {
      out.sum = total;
      out.cells = n;
      if (total > kTwoPi * (1 + 1e-6))
        return true;
      double e1[Dim], e2[Dim] = {}, u[Dim];
      project(f0, nb, fans_[0].p, e1);
      const double l1 = std::sqrt(dot(e1, e1));
      if (!(l1 > 0))
        return false;
      for (int d = 0; d < Dim; ++d)
        e1[d] /= l1;
      double best = 0;
      for (const Fan &f : fans_) { // e2: the most normal of the fans' first cells
        project(f0, nb, f.w, u);
        const double s = dot(u, e1);
        for (int d = 0; d < Dim; ++d)
          u[d] -= s * e1[d];
        const double l = std::sqrt(dot(u, u));
        if (l > best) {
          best = l;
          for (int d = 0; d < Dim; ++d)
            e2[d] = u[d] / l;
        }
      }
      if (!(best > 0))
        return false;
      auto direction = [&](VertexId v) {
        project(f0, nb, v, u);
        const double a = std::atan2(dot(u, e2), dot(u, e1));
        return a < 0 ? a + kTwoPi : a;
      };
      intervals_.clear();
      for (const Fan &f : fans_) {
        const double a = direction(f.p), b = direction(f.w);
        double turn = b - a; // from p towards w: counter-clockwise in (e1, e2)?
        if (turn < -M_PI)
          turn += kTwoPi;
        else if (turn > M_PI)
          turn -= kTwoPi;
        double lo = turn >= 0 ? a : a - f.sum;
        if (lo < 0)
          lo += kTwoPi;
        intervals_.push_back({lo, lo + f.sum});
      }
      std::sort(intervals_.begin(), intervals_.end());
      const double tol = 1e-6 * kTwoPi;
      for (std::size_t i = 0; i < intervals_.size(); ++i) {
        const double next =
            i + 1 < intervals_.size() ? intervals_[i + 1].first : intervals_[0].first + kTwoPi;
        if (intervals_[i].second > next + tol) {
          out.expected = -1; // fans overlapping
          return true;
        }
      }
    }
    return false;
  }

private:
  // Whether the angles of a fan of cells from boundary facet F + p to F + q,
  // summing to `sum`, fill the interior angle between them: from ray p to
  // ray q, turning towards w (the other vertex of p's cell), in [0, 2π).
  bool boundary_angle_fits(const double *f0, int nb, VertexId p, VertexId w, VertexId q, double sum,
                           double &expected) const {
    constexpr double kTwoPi = 2 * M_PI;
    double up[Dim], uq[Dim], uw[Dim];
    project(f0, nb, p, up);
    project(f0, nb, q, uq);
    project(f0, nb, w, uw);
    // e1 = up / |up|, e2 = the part of uw normal to e1, normalized.
    const double lp = std::sqrt(dot(up, up));
    const double sw = dot(uw, up) / (lp * lp);
    for (int d = 0; d < Dim; ++d)
      uw[d] -= sw * up[d];
    const double lw = std::sqrt(dot(uw, uw));
    expected = sum;
    if (!(lp > 0) || !(lw > 0))
      return true;
    const double x = dot(uq, up) / lp, y = dot(uq, uw) / lw;
    const double a = std::atan2(y, x); // in (-π, π]
    expected = a >= 0 ? a : kTwoPi + a;
    if (std::abs(sum - expected) <= M_PI)
      return true;
    // Rays p and q nearly aligned (a needle-like boundary): which side q is
    // on is below rounding; then 0 and 2π are both plausible.
    const double lq = std::sqrt(dot(uq, uq));
    if (std::abs(y) <= 1e-8 * lq && x > 0) {
      const double alt = expected < M_PI ? expected + kTwoPi : expected - kTwoPi;
      if (std::abs(sum - alt) <= M_PI)
        return true;
    }
    return false;
  }

  static double dot(const double *a, const double *b) {
    double s = 0;
    for (int d = 0; d < Dim; ++d)
      s += a[d] * b[d];
    return s;
  }
  void project(const double *f0, int nb, VertexId v, double *u) const {
    const double *x = mesh_->point(v);
    for (int d = 0; d < Dim; ++d)
      u[d] = x[d] - f0[d];
    for (int j = 0; j < nb; ++j) {
      const double s = dot(u, basis_[j]);
      for (int d = 0; d < Dim; ++d)
        u[d] -= s * basis_[j][d];
    }
  }
  // The angle between u and v is atan2(y, x) of these (y >= 0): y from the
  // part of u normal to v, so that small angles lose nothing to cancellation.
  static std::pair<double, double> sides(const double *u, const double *v) {
    const double vv = dot(v, v), uv = dot(u, v);
    double w2 = 0;
    for (int d = 0; d < Dim; ++d) {
      const double r = u[d] - uv / vv * v[d];
      w2 += r * r;
    }
    return {std::sqrt(w2 * vv), uv};
  }

  const Mesh *mesh_;
  double basis_[Dim > 2 ? Dim - 2 : 1][Dim];
  std::vector<double> angle_;
  std::vector<std::pair<double, double>> wedge_; // sides() per cell
  std::vector<std::pair<VertexId, int>> entry_;
  std::vector<char> seen_;
  struct Fan {
    VertexId p, w; // first end; the other vertex of its cell
    double sum;
  };
  std::vector<Fan> fans_;
  std::vector<std::pair<double, double>> intervals_;
};

// e.g. "tangled: the 7 cells around edge (3, 9) have dihedral angles summing
// to 720 degrees, expected 360 (a full turn)"
std::string angle_message(const std::string &face, const AngleFinding &f, int dim) {
  char buf[200];
  if (f.expected < 0) {
    std::snprintf(buf, sizeof buf,
                  " form fans (a pinch) that overlap; their %sangles sum to %.6g degrees",
                  dim == 2 ? "" : "dihedral ", f.sum * 180 / M_PI);
    return "tangled: the " + std::to_string(f.cells) + " cells around " + face + buf;
  }
  std::snprintf(buf, sizeof buf, " have %sangles summing to %.6g degrees, expected %.6g (%s)",
                dim == 2 ? "" : "dihedral ", f.sum * 180 / M_PI, f.expected * 180 / M_PI,
                f.boundary ? "the interior angle of the boundary there" : "a full turn");
  return "tangled: the " + std::to_string(f.cells) + " cells around " + face + buf;
}

// Whether the angle check skips face `key` (sorted ids): where the count is
// surely 1 around its centroid (summed in key order, the same for every
// cell), its cells go round it once. A test may ask for the skipped faces.
template <int Dim, std::size_t K>
bool wound_once_at(const Mesh &mesh, const WoundBoxes<Dim> &wound,
                   const std::array<VertexId, K> &key) {
  double mid[Dim] = {};
  for (VertexId v : key)
    for (int d = 0; d < Dim; ++d)
      mid[d] += mesh.point(v)[d];
  for (int d = 0; d < Dim; ++d)
    mid[d] /= double(K);
  if (!wound.one_at(mid))
    return false;
  if (g_skipped_faces) {
    std::lock_guard<std::mutex> lock(g_skipped_faces_mutex);
    g_skipped_faces->emplace_back(key.begin(), key.end());
  }
  return true;
}

// The face visitor of find_fold (3D, 4D): the star of each
// codimension-2 face, until the first tangled one.
template <int Dim> struct FoldVisitor {
  static constexpr int N = Dim + 1;
  static constexpr auto subsets = subsimplices<N, Dim - 1>();
  static constexpr int M = int(subsets.size());
  const Mesh *mesh;
  StarAngles<Dim> star;
  std::vector<VertexId> extras;
  AngleFinding f;
  std::string found;
  std::size_t faces = 0; // distinct faces visited
  const WoundBoxes<Dim> *wound = nullptr;
  explicit FoldVisitor(const Mesh &m, const WoundBoxes<Dim> *w = nullptr)
      : mesh(&m), star(m), wound(w) {}
  void operator()(const std::array<VertexId, Dim - 1> &key, const std::uint32_t *refs, int count) {
    ++faces;
    if (!found.empty())
      return;
    if (wound && wound_once_at(*mesh, *wound, key))
      return;
    extras.clear();
    for (int i = 0; i < count; ++i) {
      const VertexId *cell = mesh->cell(CellId(refs[i] / M));
      const auto &in = subsets[refs[i] % M];
      for (int k = 0; k < N; ++k)
        if (std::find(in.begin(), in.end(), k) == in.end())
          extras.push_back(cell[k]);
    }
    if (star.tangled(key.data(), extras.data(), count, f))
      found = angle_message((Dim == 3 ? "edge " : "triangle ") + id_list(*mesh, key), f, Dim);
  }
};

// The offsets of a counting sort of the cells' vertex slots by vertex:
// vertex v's slots go to start[v] .. start[v + 1].
std::vector<std::size_t> vertex_offsets(const Mesh &mesh) {
  const std::size_t nv = mesh.num_vertices();
  std::vector<std::size_t> start(nv + 1, 0);
  for (VertexId v : mesh.cells)
    ++start[v + 1];
  for (std::size_t v = 1; v <= nv; ++v)
    start[v] += start[v - 1];
  return start;
}

// The cells by vertex (counting sort by vertex_offsets, each vertex's cells
// in cell order): vertex v's cells are star[start[v]] .. star[start[v + 1]].
// Each thread scans all cells and files those of its range of vertices.
std::vector<CellId, UninitialisedAllocator<CellId>>
vertex_stars(const Mesh &mesh, const std::vector<std::size_t> &start) {
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  const int n = mesh.cell_size();
  std::vector<CellId, UninitialisedAllocator<CellId>> star(mesh.cells.size());
  const int parts = int(std::clamp<std::size_t>(nc >> 16, 1, std::size_t(threads())));
  std::vector<std::size_t> cursor(start.begin(), start.end() - 1);
#pragma omp parallel for num_threads(parts) schedule(static, 1)
  for (int t = 0; t < parts; ++t) {
    const VertexId lo = VertexId(nv * std::size_t(t) / std::size_t(parts)),
                   hi = VertexId(nv * std::size_t(t + 1) / std::size_t(parts));
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *cell = mesh.cell(CellId(c));
      for (int i = 0; i < n; ++i)
        if (cell[i] >= lo && cell[i] < hi)
          star[cursor[cell[i]]++] = CellId(c);
    }
  }
  return star;
}

// What the angle check's blocks found: their face counts added into *faces
// (when asked), and the first finding in block order (empty if none).
std::string first_finding(const std::vector<std::string> &found,
                          const std::vector<std::size_t> &counts, std::size_t *faces) {
  if (faces) {
    *faces = 0;
    for (std::size_t n : counts)
      *faces += n;
  }
  for (const std::string &m : found)
    if (!m.empty())
      return m;
  return {};
}

// find_fold in 4D, from the stars of the vertices: the triangles by their
// smallest vertex v, and among those by their middle one w. A thread marks
// each larger neighbour w of v the first time v's star meets it (stamp),
// files v's cells by w (a counting sort, so each edge's cells stay in cell
// order), then for each w marks the largest vertices u of the edge's cells
// (tick). Every distinct triangle is so counted once, and tested as the
// walk over all triangles (FoldVisitor) tests it: the same skip at its
// centroid (summed in key order), its cells in cell order with their other
// two vertices in their own order; findings in key order. The walk sorted
// the ten triangles of every cell (52 M for 5.2 M pentatopes).
std::string find_fold4_stars(const Mesh &mesh, std::size_t *faces, const WoundBoxes<4> *wound) {
  constexpr int N = 5;
  const std::size_t nv = mesh.num_vertices();
  const std::vector<std::size_t> start = vertex_offsets(mesh);
  const auto star = vertex_stars(mesh, start);
  constexpr std::size_t kBlock = std::size_t(1) << 11;
  const std::size_t blocks = (nv + kBlock - 1) / kBlock;
  std::vector<std::string> found(blocks);
  std::vector<std::size_t> triangles(blocks, 0);
  const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel num_threads(workers)
  {
    StarAngles<4> angles(mesh);
    AngleFinding f;
    std::vector<VertexId> stamp(nv, kNoVertex), local(nv), ws, us, extras;
    std::vector<std::uint32_t> tick(nv, 0);
    std::uint32_t ticks = 0;
    std::vector<std::size_t> first; // per w: where its cells start in `edge`
    std::vector<CellId> edge;       // v's cells, by w
#pragma omp for schedule(dynamic, 1)
    for (std::size_t k = 0; k < blocks; ++k)
      for (std::size_t v = k * kBlock; v < std::min(nv, (k + 1) * kBlock); ++v) {
        const VertexId vv = VertexId(v);
        ws.clear();
        for (std::size_t s = start[v]; s < start[v + 1]; ++s) {
          const VertexId *cell = mesh.cell(star[s]);
          for (int i = 0; i < N; ++i)
            if (cell[i] > vv && stamp[cell[i]] != vv) {
              stamp[cell[i]] = vv;
              ws.push_back(cell[i]);
            }
        }
        if (ws.empty())
          continue;
        std::sort(ws.begin(), ws.end());
        first.assign(ws.size() + 1, 0);
        for (std::size_t i = 0; i < ws.size(); ++i)
          local[ws[i]] = VertexId(i);
        for (std::size_t s = start[v]; s < start[v + 1]; ++s) {
          const VertexId *cell = mesh.cell(star[s]);
          for (int i = 0; i < N; ++i)
            if (cell[i] > vv)
              ++first[local[cell[i]] + 1];
        }
        for (std::size_t i = 1; i <= ws.size(); ++i)
          first[i] += first[i - 1];
        edge.resize(first.back());
        for (std::size_t s = start[v]; s < start[v + 1]; ++s) {
          const VertexId *cell = mesh.cell(star[s]);
          for (int i = 0; i < N; ++i)
            if (cell[i] > vv)
              edge[first[local[cell[i]]]++] = star[s];
        }
        // first[i] is now where w_i's cells end; they start at first[i - 1].
        for (std::size_t i = 0; i < ws.size(); ++i) {
          const VertexId w = ws[i];
          const std::size_t b = i == 0 ? 0 : first[i - 1], e = first[i];
          if (++ticks == 0) { // wrapped: clear the marks
            std::fill(tick.begin(), tick.end(), 0);
            ticks = 1;
          }
          us.clear();
          for (std::size_t j = b; j < e; ++j) {
            const VertexId *cell = mesh.cell(edge[j]);
            for (int q = 0; q < N; ++q)
              if (cell[q] > w && tick[cell[q]] != ticks) {
                tick[cell[q]] = ticks;
                us.push_back(cell[q]);
              }
          }
          triangles[k] += us.size();
          if (!found[k].empty())
            continue;
          std::sort(us.begin(), us.end());
          for (const VertexId u : us) {
            const std::array<VertexId, 3> key{vv, w, u};
            if (wound && wound_once_at(mesh, *wound, key))
              continue;
            extras.clear();
            int count = 0;
            for (std::size_t j = b; j < e; ++j) {
              const VertexId *cell = mesh.cell(edge[j]);
              if (std::find(cell, cell + N, u) == cell + N)
                continue;
              ++count;
              for (int q = 0; q < N; ++q)
                if (cell[q] != vv && cell[q] != w && cell[q] != u)
                  extras.push_back(cell[q]);
            }
            if (angles.tangled(key.data(), extras.data(), count, f)) {
              found[k] = angle_message("triangle " + id_list(mesh, key), f, 4);
              break;
            }
          }
        }
      }
  }
  return first_finding(found, triangles, faces);
}

// `faces`, when given and in 3D or 4D, receives the number of distinct faces of
// Dim - 1 vertices (edges in 3D, triangles in 4D).
// With `wound` (from centroids_wound_once), faces where the count is surely
// 1 all around are skipped: a face whose cells went round it k times would
// have count k near it.
template <int Dim>
std::string find_fold(const Mesh &mesh, std::size_t *faces = nullptr,
                      const WoundBoxes<Dim> *wound = nullptr) {
  if constexpr (Dim == 2) {
    constexpr int N = Dim + 1;
    const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
    // The faces are the vertices: cells by vertex (counting sort).
    const std::vector<std::size_t> start = vertex_offsets(mesh);
    std::vector<VertexId> pairs(2 * mesh.cells.size());
    std::vector<std::size_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *cell = mesh.cell(CellId(c));
      for (int i = 0; i < N; ++i) {
        const std::size_t at = 2 * cursor[cell[i]]++;
        pairs[at] = cell[(i + 1) % N];
        pairs[at + 1] = cell[(i + 2) % N];
      }
    }
    // Blocks of vertices by all threads; the first finding in block order.
    constexpr std::size_t kBlock = std::size_t(1) << 12;
    const std::size_t blocks = (nv + kBlock - 1) / kBlock;
    std::vector<std::string> found(blocks);
    const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel num_threads(workers)
    {
      StarAngles<Dim> star(mesh);
      AngleFinding f;
#pragma omp for schedule(dynamic, 1)
      for (std::size_t k = 0; k < blocks; ++k)
        for (std::size_t v = k * kBlock; v < std::min(nv, (k + 1) * kBlock); ++v) {
          const int n = int(start[v + 1] - start[v]);
          const VertexId face = VertexId(v);
          if (wound && wound->one_at(mesh.point(face))) {
            if (g_skipped_faces) {
              std::lock_guard<std::mutex> lock(g_skipped_faces_mutex);
              g_skipped_faces->push_back({face});
            }
            continue;
          }
          if (n > 0 && star.tangled(&face, &pairs[2 * start[v]], n, f)) {
            found[k] = angle_message(vertex_name(mesh, VertexId(v)), f, 2);
            break;
          }
        }
    }
    for (const std::string &s : found)
      if (!s.empty())
        return s;
    return {};
  } else if constexpr (Dim == 3) {
    // The edges by their smaller end v, from v's star (the cells by vertex,
    // a counting sort, in cell order): a thread marks each larger end w it
    // meets in v's star with stamp[w] = v, so the distinct edges are counted
    // and an edge's cells found without sorting all 6 edges of every cell.
    // On a 5.4M-tet mesh, where all but 0.4% of the edges are skipped as
    // wound once, that walk took 0.85-0.93 s (2 threads), this 0.55-0.6 s,
    // in less memory (4 bytes per cell and vertex). The cells around an
    // edge come in cell order, each one's other two vertices in its own
    // order: what the walk handed to the same test.
    constexpr int N = Dim + 1;
    const std::size_t nv = mesh.num_vertices();
    const std::vector<std::size_t> start = vertex_offsets(mesh);
    const auto star = vertex_stars(mesh, start);
    // Blocks of vertices by all threads; the first finding in block order,
    // which is key order.
    constexpr std::size_t kBlock = std::size_t(1) << 12, kAhead = 16;
    const std::size_t blocks = (nv + kBlock - 1) / kBlock;
    std::vector<std::string> found(blocks);
    std::vector<std::size_t> edges(blocks, 0);
    const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel num_threads(workers)
    {
      StarAngles<Dim> angles(mesh);
      AngleFinding f;
      std::vector<VertexId> stamp(nv, kNoVertex), ends, extras;
#pragma omp for schedule(dynamic, 1)
      for (std::size_t k = 0; k < blocks; ++k)
        for (std::size_t v = k * kBlock; v < std::min(nv, (k + 1) * kBlock); ++v) {
          ends.clear();
          const double *p = mesh.point(VertexId(v));
          for (std::size_t s = start[v]; s < start[v + 1]; ++s) {
            if (s + kAhead < star.size())
              __builtin_prefetch(mesh.cell(star[s + kAhead]));
            const VertexId *cell = mesh.cell(star[s]);
            for (int i = 0; i < N; ++i) {
              const VertexId w = cell[i];
              if (w <= v || stamp[w] == VertexId(v))
                continue;
              stamp[w] = VertexId(v);
              ++edges[k];
              if (wound) {
                // Where the count is surely 1 around the edge's midpoint,
                // its cells go round it once.
                const double *q = mesh.point(w);
                double mid[Dim];
                for (int d = 0; d < Dim; ++d)
                  mid[d] = (0.0 + p[d] + q[d]) / 2;
                if (wound->one_at(mid)) {
                  if (g_skipped_faces) {
                    std::lock_guard<std::mutex> lock(g_skipped_faces_mutex);
                    g_skipped_faces->push_back({VertexId(v), w});
                  }
                  continue;
                }
              }
              ends.push_back(w);
            }
          }
          if (!found[k].empty())
            continue;
          std::sort(ends.begin(), ends.end());
          for (VertexId w : ends) {
            const std::array<VertexId, 2> key{VertexId(v), w};
            extras.clear();
            int count = 0;
            for (std::size_t s = start[v]; s < start[v + 1]; ++s) {
              const VertexId *cell = mesh.cell(star[s]);
              if (std::find(cell, cell + N, w) == cell + N)
                continue;
              ++count;
              for (int i = 0; i < N; ++i)
                if (cell[i] != VertexId(v) && cell[i] != w)
                  extras.push_back(cell[i]);
            }
            if (angles.tangled(key.data(), extras.data(), count, f)) {
              found[k] = angle_message("edge " + id_list(mesh, key), f, Dim);
              break;
            }
          }
        }
    }
    return first_finding(found, edges, faces);
  } else if constexpr (Dim == 4) {
    if (!g_walk_fold4) {
      return find_fold4_stars(mesh, faces, wound);
    }
    // The faces' stars in blocks of the walk, by all threads; the first
    // finding in block order (key order), as one walk in one thread.
    std::vector<FoldVisitor<Dim>> parts;
    for_each_subsimplex_blocks<Dim, Dim - 1>(mesh, FoldVisitor<Dim>(mesh, wound), parts);
    if (faces) {
      *faces = 0;
      for (const FoldVisitor<Dim> &part : parts)
        *faces += part.faces;
    }
    for (const FoldVisitor<Dim> &part : parts)
      if (!part.found.empty())
        return part.found;
    return {};
  }
}

bool relative_change(double before, double after) {
  const double scale = std::max(std::abs(before), std::abs(after));
  return std::abs(after - before) > 1e-9 * scale;
}

} // namespace

Invariants measure_invariants(const Mesh &mesh, bool euler) {
  if (mesh.num_cells() == 0)
    return {};
  return dispatch(mesh.dim, [&]<int D>() {
    Invariants inv;
    std::size_t bad;
    double bad_volume = 0;
    inv.volume = cell_pass<D>(mesh, bad, bad_volume);
    const FacetReport fr = facet_pass<D>(mesh, nullptr, false);
    inv.boundary_measure = fr.boundary_measure;
    inv.boundary_facets = fr.boundary_facets;
    if (euler)
      inv.euler = euler_characteristic<D>(mesh, fr.facets);
    return inv;
  });
}

// "cell 7 is degenerate (volume 1e-20)", for the checks of a whole mesh.
static std::string degenerate_cell(const Mesh &mesh, std::size_t cell, double volume) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", volume);
  return cell_name(mesh, CellId(cell)) + " is degenerate (volume " + buf + ")";
}

CheckResult check_conformity(const Mesh &mesh, const Invariants *original,
                             const CheckOptions &options) {
  auto fail = [](std::string what) { return CheckResult{false, std::move(what)}; };
  if (std::string s = check_shape(mesh); !s.empty())
    return fail(s);
  if (std::string s = check_ids(mesh); !s.empty())
    return fail(s);
  return dispatch(mesh.dim, [&]<int D>() {
    std::size_t bad;
    double bad_volume = 0;
    std::vector<std::int8_t> signs;
    const double volume = cell_pass<D>(mesh, bad, bad_volume, &signs);
    if (bad != std::size_t(-1))
      return fail(degenerate_cell(mesh, bad, bad_volume));
    const FacetReport fr = facet_pass<D>(mesh, &signs, true);
    if (!fr.nonmanifold.empty())
      return fail(fr.nonmanifold);
    if (!fr.overlap.empty())
      return fail(fr.overlap);
    // See CheckOptions: for a refined mesh the boundary measure finds every
    // defect the search would, while each boundary facet is well above the
    // measure's tolerance.
    const bool measure_suffices = options.refined_from_original && original &&
                                  fr.smallest_boundary_facet > 1e-8 * fr.boundary_measure;
    if (!measure_suffices)
      if (std::string s = find_hanging_node<D>(mesh, fr.boundary); !s.empty())
        return fail(s);
    if (original) {
      // The Euler characteristic (an edge walk) only when the rest agrees.
      Invariants now{volume, fr.boundary_measure, original->euler, fr.boundary_facets};
      if (CheckResult r = compare_invariants(*original, now); !r.ok)
        return r;
      now.euler = euler_characteristic<D>(mesh, fr.facets);
      return compare_invariants(*original, now);
    }
    return CheckResult{};
  });
}

CheckResult compare_invariants(const Invariants &original, const Invariants &now) {
  auto fail = [](std::string what) { return CheckResult{false, std::move(what)}; };
  if (relative_change(original.volume, now.volume))
    return fail(format("volume changed: %.10g -> %.10g (relative %.2g)", original.volume,
                       now.volume,
                       std::abs(now.volume - original.volume) / std::abs(original.volume)));
  if (relative_change(original.boundary_measure, now.boundary_measure))
    return fail(format("boundary measure changed: %.10g -> %.10g (relative %.2g)",
                       original.boundary_measure, now.boundary_measure,
                       std::abs(now.boundary_measure - original.boundary_measure) /
                           std::abs(original.boundary_measure)));
  if (now.euler != original.euler)
    return fail("Euler characteristic changed: " + std::to_string(original.euler) + " -> " +
                std::to_string(now.euler));
  return CheckResult{};
}

// The final check's facet walk. An entry packs the facet's ids after the
// smallest and the side bit, and where it can also the smallest id's place
// in its coarse bucket (FineInKey), in 64 bits: 4D while ids fit in 18
// bits (below 262,144 vertices, about 5.5 M pentatopes), 3D in 24 (below
// 16,777,216 vertices): 8 bytes an entry. Otherwise 4D packs three 21-bit
// ids (below 2,097,152 vertices) in 64 bits and larger ids in 128, 3D two
// 31-bit ids in 64, each with the 2-byte place beside it.
//
// Its buffer holds a little over half the mesh's facet entries (D + 1 per
// cell; 8 or 10 bytes each: 18-22 bytes per tet, about the size of the
// cells' own arrays), so that the walk takes two chunks; at least 16 and at
// most 160 MiB. 3D, 3,178,142 tets: 56 MB, below the last iteration's
// peak. 4D, 5,233,296 pentatopes: 115 MB (144 before FineInKey).
template <int D>
static FacetReport final_facet_pass(const Mesh &mesh, const std::vector<std::int8_t> &signs) {
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  // A little over a third of the facets (chunks end at bucket boundaries).
  // With half, this buffer made the peak of a refinement's memory; three
  // chunks take no longer than two (bench/e2e.sh, 2 threads: 3.2 M-tet
  // ball 0.13-0.17 s, 5.2 M pentatopes 0.2-0.3 s either way). The 4D peak
  // went from 57-58 to 49-50 bytes per pentatope; in 3D the last iteration
  // now makes the peak (3.2 M tets: 211 MB in the check before, 190 now).
  auto budget = [&](std::size_t entry_bytes) {
    return std::clamp(nc * std::size_t(D + 1) * entry_bytes * 7 / 20, std::size_t(16) << 20,
                      std::size_t(160) << 20);
  };
  if constexpr (D == 3) {
    if (!g_wide_final_walk && Walk<3, 3, true, true, 24, true>::fits(nv, nc))
      return facet_pass<D, true, 24, true>(mesh, &signs, true, nullptr, budget(8));
  }
  if constexpr (D == 4) {
    if (!g_wide_final_walk && Walk<4, 4, true, true, 18, true>::fits(nv, nc))
      return facet_pass<D, true, 18, true>(mesh, &signs, true, nullptr, budget(8));
    if (nv < (std::size_t(1) << 21))
      return facet_pass<D, true, 21>(mesh, &signs, true, nullptr, budget(10));
  }
  return facet_pass<D, true>(mesh, &signs, true, nullptr, budget(D == 4 ? 18 : 10));
}

// The quality summary is the checks' cell pass with the mean ratio: one
// loop, so quality_with_cell_facts gives the same figures by construction.
QualitySummary quality_summary(const Mesh &mesh) {
  if (mesh.num_cells() == 0 || !check_shape(mesh).empty())
    return {};
  return dispatch(mesh.dim, [&]<int D>() {
    QualitySummary q;
    std::size_t bad;
    double bad_volume = 0;
    cell_pass<D>(mesh, bad, bad_volume, nullptr, nullptr, &q);
    return q;
  });
}

QualitySummary quality_with_cell_facts(const Mesh &mesh, CellFacts &facts) {
  facts = CellFacts{};
  if (!check_shape(mesh).empty() || mesh.num_cells() == 0)
    return quality_summary(mesh); // no facts: check_refined walks the cells itself
  QualitySummary q;
  dispatch(mesh.dim, [&]<int D>() {
    facts.volume = cell_pass<D>(mesh, facts.first_degenerate, facts.its_volume, &facts.signs,
                                &facts.ids_ok, &q);
  });
  facts.cells = mesh.cells.data();
  facts.coords = mesh.coords.data();
  facts.num_cells = mesh.num_cells();
  facts.num_vertices = mesh.num_vertices();
  return q;
}

CheckResult check_refined(const Mesh &mesh, const Invariants &original, const CellFacts *facts) {
  auto fail = [](std::string what) { return CheckResult{false, std::move(what)}; };
  if (std::string s = check_shape(mesh); !s.empty())
    return fail(s);
  if (mesh.num_cells() == 0)
    return CheckResult{};
  return dispatch(mesh.dim, [&]<int D>() {
    std::size_t bad;
    double bad_volume = 0;
    std::vector<std::int8_t> own_signs;
    bool ids_ok = true;
    const bool taken = facts && facts->describe(mesh);
    const double volume =
        taken ? facts->volume : cell_pass<D>(mesh, bad, bad_volume, &own_signs, &ids_ok);
    if (taken) {
      bad = facts->first_degenerate;
      bad_volume = facts->its_volume;
      ids_ok = facts->ids_ok;
    }
    const std::vector<std::int8_t> &signs = taken ? facts->signs : own_signs;
    if (!ids_ok)
      return fail(check_ids(mesh));
    if (bad != std::size_t(-1))
      return fail(degenerate_cell(mesh, bad, bad_volume));
    const FacetReport fr = mesh.num_vertices() < std::size_t(kSideBit)
                               ? final_facet_pass<D>(mesh, signs)
                               : facet_pass<D>(mesh, &signs, true);
    if (!fr.nonmanifold.empty())
      return fail(fr.nonmanifold);
    if (!fr.overlap.empty())
      return fail(fr.overlap);
    if (relative_change(original.volume, volume))
      return fail(format("volume changed: %.10g -> %.10g (relative %.2g)", original.volume, volume,
                         std::abs(volume - original.volume) / std::abs(original.volume)));
    if (relative_change(original.boundary_measure, fr.boundary_measure))
      return fail(format("boundary measure changed: %.10g -> %.10g (relative %.2g; a hanging node "
                         "or a face split differently from its two sides)",
                         original.boundary_measure, fr.boundary_measure,
                         std::abs(fr.boundary_measure - original.boundary_measure) /
                             std::abs(original.boundary_measure)));
    if (!(fr.smallest_boundary_facet > 1e-8 * fr.boundary_measure))
      if (std::string s = find_hanging_node<D>(mesh, fr.boundary); !s.empty())
        return fail(s);
    return CheckResult{};
  });
}

void for_each_interior_facet(const Mesh &mesh,
                             const std::function<bool(CellId, int, CellId, int)> &visit) {
  if (mesh.num_cells() == 0)
    return;
  dispatch(mesh.dim, [&]<int D>() {
    constexpr int M = D + 1;
    bool going = true;
    for_each_subsimplex<D, D>(
        mesh, [&](const std::array<VertexId, D> &, const std::uint32_t *refs, int count) {
          if (!going || count != 2)
            return;
          going = visit(CellId(refs[0] / M), opposite_of_facet<D>(int(refs[0] % M)),
                        CellId(refs[1] / M), opposite_of_facet<D>(int(refs[1] % M)));
        });
  });
}

void for_each_interior_facet(const Mesh &mesh, const std::vector<std::array<CellId, 2>> &piece,
                             const std::function<bool(CellId, int, CellId, int)> &visit) {
  const int n = mesh.cell_size();
  // The local index in x of the vertex not in y.
  auto opposite = [&](const VertexId *x, const VertexId *y) {
    for (int i = 0; i < n; ++i)
      if (std::find(y, y + n, x[i]) == y + n)
        return i;
    return 0;
  };
  // The two cells of a facet lie anywhere in the cell arrays: their rows
  // (and, when marked, their stage and tag, which visitors read) are
  // fetched a few facets ahead, so that the cache misses overlap.
  constexpr std::size_t kAhead = 12;
  const bool marked = mesh.marked();
  for (std::size_t k = 0; k < piece.size(); ++k) {
    if (k + kAhead < piece.size())
      for (CellId c : piece[k + kAhead]) {
        __builtin_prefetch(mesh.cell(c));
        if (marked) {
          __builtin_prefetch(&mesh.stage[c]);
          __builtin_prefetch(&mesh.tag[c]);
        }
      }
    const auto [a, b] = piece[k];
    const VertexId *x = mesh.cell(a), *y = mesh.cell(b);
    if (!visit(a, opposite(x, y), b, opposite(y, x)))
      return;
  }
}

void for_each_interior_facet(const Mesh &mesh, const InteriorFacets &facets,
                             const std::function<bool(CellId, int, CellId, int)> &visit) {
  bool going = true;
  for (const auto &piece : facets) {
    for_each_interior_facet(
        mesh, piece, [&](CellId a, int i, CellId b, int j) { return going = visit(a, i, b, j); });
    if (!going)
      return;
  }
}

void prepare_input(Mesh &mesh, const std::string &path, const LoadProgress &progress,
                   InputFacts *facts) {
  // The fractions are the steps' shares of `bisect info`'s time on a
  // 1.85M-tet .vtu (the read before them about 0.3).
  auto step = [&](const char *what, double done) {
    if (progress)
      progress(what, done);
  };
  step("checking cells", 0.3);
  if (std::string s = check_shape(mesh); !s.empty())
    throw InputError(path, s);
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  for (std::size_t v = 0; v < nv; ++v)
    for (int d = 0; d < mesh.dim; ++d)
      if (!std::isfinite(mesh.point(VertexId(v))[d]))
        throw InputError(path, vertex_name(mesh, VertexId(v)) + " has a non-finite coordinate");
  if (std::string s = check_ids(mesh); !s.empty())
    throw InputError(path, s);
  const int n = mesh.cell_size();
  for (std::size_t c = 0; c < nc; ++c) {
    const VertexId *cell = mesh.cell(CellId(c));
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (cell[i] == cell[j])
          throw InputError(path,
                           cell_name(mesh, CellId(c)) + " repeats " + vertex_name(mesh, cell[i]));
  }
  // A mesh that fails a check below and has coincident duplicate vertices
  // (exported without merging nodes: zero-volume cells, hanging nodes, ...)
  // is reported by its duplicates, the cause; looked for only on failure.
  auto reject = [&](const std::string &what) {
    if (std::string d = find_duplicate_cells(mesh); !d.empty())
      throw InputError(path, d);
    if (std::string d = find_duplicate_vertices(mesh); !d.empty())
      throw InputError(path, d);
    throw InputError(path, what);
  };
  dispatch(mesh.dim, [&]<int D>() {
    std::size_t bad;
    double bad_volume = 0;
    std::vector<std::int8_t> signs;
    const double volume =
        cell_pass<D>(mesh, bad, bad_volume, &signs, nullptr,
                     facts && facts->want_quality && nc > 0 ? &facts->quality : nullptr);
    if (bad != std::size_t(-1))
      reject(cell_name(mesh, CellId(bad)) + " has zero volume");
    step("matching facets", 0.4);
    const FacetReport fr = facet_pass<D>(
        mesh, &signs, true, facts && facts->want_interior ? &facts->interior : nullptr);
    if (!fr.nonmanifold.empty()) {
      // "facet (a, b) is shared by 3 cells" -> "non-manifold: facet (a, b) shared by 3 cells"
      std::string s = fr.nonmanifold;
      s.replace(s.find(" is shared"), 10, " shared");
      reject("non-manifold: " + s);
    }
    if (!fr.overlap.empty())
      reject("tangled: " + fr.overlap);
    step("looking for hanging nodes", 0.55);
    if (std::string s = find_hanging_node<D>(mesh, fr.boundary); !s.empty())
      reject("non-conforming input: " + s);
    step("looking for overlapping cells", 0.6);
    WoundBoxes<D> wound;
    const bool sure = g_overlap_fast_path &&
                      centroids_wound_once<D>(mesh, fr.boundary, fr.boundary_opposite, &wound);
    if (!sure)
      if (std::string s = find_overlap<D>(mesh); !s.empty())
        reject("tangled: " + s);
    step("checking the angles around faces", 0.75);
    std::size_t ridges = std::size_t(-1);
    if (std::string s = find_fold<D>(mesh, &ridges, sure ? &wound : nullptr); !s.empty())
      reject(s);
    // What the walks found, for the caller (the same values as
    // measure_invariants: the same passes, summed in the same order).
    if (facts) {
      facts->invariants.volume = volume;
      facts->invariants.boundary_measure = fr.boundary_measure;
      facts->invariants.boundary_facets = fr.boundary_facets;
      facts->invariants.euler = euler_characteristic<D>(mesh, fr.facets, ridges);
    }
    // Orient every cell positively (a negatively oriented cell is not an error).
    for (std::size_t c = 0; c < nc; ++c)
      if (signs[c] < 0)
        std::swap(mesh.cell(CellId(c))[0], mesh.cell(CellId(c))[1]);
  });
}

} // namespace bisect

namespace bisect::testing {
void set_walk_chunk_bytes(std::size_t bytes) {
  g_chunk_bytes = bytes;
}

void set_final_walk_piece(std::size_t entries) {
  g_match_piece = entries ? entries : kMatchPiece;
}

void use_sorted_final_walk(bool on) {
  g_sorted_final_walk = on;
}
void use_wide_final_walk(bool on) {
  g_wide_final_walk = on;
}
void use_walk_fold4(bool on) {
  g_walk_fold4 = on;
}
void use_narrow_facet_walk(bool on) {
  g_narrow_facet_walk = on;
}
double rough_angle(double y, double x) {
  return bisect::rough_angle({y, x});
}
void use_own_overlap_search(bool on) {
  g_own_overlap_search = on;
}
void use_overlap_fast_path(bool on) {
  g_overlap_fast_path = on;
}
bool overlap_fast_path_taken() {
  return g_overlap_fast_path_taken;
}
void record_skipped_faces(std::vector<std::vector<VertexId>> *out) {
  g_skipped_faces = out;
}
} // namespace bisect::testing
