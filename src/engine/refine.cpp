// Refine to conformity by bisection (ALGORITHMS.md §1, §6; seed 000 Procedure
// 1; seed 002 §4). The kernels are templated on the dimension and
// instantiated for 2, 3 and 4 in one place (dispatch at the bottom).
//
// One pass bisects a list of cells in place: child 1 takes the parent's slot,
// child 2 is appended. Midpoints are shared through a hash map from the edge
// (sorted id pair) to the new vertex, cleared after every iteration: once an
// iteration is conforming no cell has an edge that was bisected.
//
// Tagged entities (mesh.hpp) split with the cells: when a cell is bisected
// at (a, b), its faces that are entities and hold a and b are replaced by
// their halves (entities.hpp). A mesh without entities has no splitter.
#include "bisect/refine.hpp"

#include "bisect/mark.hpp"
#include "bisect/threads.hpp"
#include "core/dimension.hpp"
#include "core/numbering.hpp"
#include "engine/entities.hpp"
#include "engine/refine_testing.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <omp.h>
#include <stdexcept>
#include <type_traits>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define BISECT_SCAN_AVX2 1
#endif

namespace bisect {

namespace testing {
int midpoint_room();
void count_midpoint_retry();
bool vector_scan();
int walk_around();
void count_walk();
} // namespace testing

namespace {

// The closure's scan (Refiner::run) over the cells [lo, hi) of `cells` (N
// ids each): ends = the bits of a cell's vertices set in `flag` (bit i:
// x[i]); keep(c, ends) decides, and is asked only for the cells with a bit
// set in `bisected` or with two flagged vertices (no other can be kept).
template <int N, class Keep>
void scan_flagged_scalar(const VertexId *cells, std::size_t lo, std::size_t hi,
                         const std::uint64_t *flag, const std::uint64_t *bisected, Keep &keep) {
  for (std::size_t c = lo; c < hi; ++c) {
    const VertexId *x = cells + c * N;
    unsigned ends = 0;
    for (int i = 0; i < N; ++i)
      ends |= unsigned(flag[x[i] >> 6] >> (x[i] & 63) & 1) << i;
    if ((bisected[c >> 6] >> (c & 63) & 1) || (ends & (ends - 1)))
      keep(c, ends);
  }
}

#ifdef BISECT_SCAN_AVX2
// The same, eight cells at a time: their 8N ids are N vectors of eight, and
// each id's flag is gathered from the bit set read as 32-bit words. Late
// passes flag a few thousand vertices among millions of cells, so nearly
// every group of eight has no two flags and is passed over in one test.
// ALGORITHMS §6's closure is unchanged: keep() still decides. 3D ball, 12
// iterations, one thread, 124.7 M cells scanned, runs alternated: passes
// with fewer than 1,000 new midpoints 1.54-2.08 ns a cell against 2.25-3.29
// one at a time; the whole scan 0.46-0.58 s against 0.51-0.72 s, the rest
// being keep()'s lookups in the midpoint table in the first passes of an
// iteration. Prefetching those lookups one group ahead made the refinement
// slower (1.16 -> 1.43 s), and was dropped.
template <int N, class Keep>
__attribute__((target("avx2"))) void scan_flagged_avx2(const VertexId *cells, std::size_t lo,
                                                       std::size_t hi, const std::uint64_t *flag,
                                                       const std::uint64_t *bisected, Keep &keep) {
  static_assert(8 * N <= 64);
  const int *words = reinterpret_cast<const int *>(flag);
  const __m256i low5 = _mm256_set1_epi32(31);
  std::size_t c = lo;
  if (c % 8 == 0)
    for (; c + 8 <= hi; c += 8) {
      const VertexId *x = cells + c * N;
      std::uint64_t ends = 0;
      for (int j = 0; j < N; ++j) {
        const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(x + 8 * j));
        const __m256i w = _mm256_i32gather_epi32(words, _mm256_srli_epi32(v, 5), 4);
        // The id's bit to the sign: bit (v & 31) shifted left by 31 - it.
        const __m256i b = _mm256_sllv_epi32(w, _mm256_sub_epi32(low5, _mm256_and_si256(v, low5)));
        ends |= std::uint64_t(unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(b)))) << (8 * j);
      }
      const unsigned bis = unsigned(bisected[c >> 6] >> (c & 63)) & 0xFFu;
      if (!bis && (ends & (ends - 1)) == 0)
        continue;
      for (int i = 0; i < 8; ++i) {
        const unsigned e = unsigned(ends >> (N * i)) & ((1u << N) - 1);
        if ((bis >> i & 1) || (e & (e - 1)))
          keep(c + i, e);
      }
    }
  scan_flagged_scalar<N>(cells, c, hi, flag, bisected, keep);
}
#endif

template <int N, class Keep>
void scan_flagged(const VertexId *cells, std::size_t lo, std::size_t hi, const std::uint64_t *flag,
                  const std::uint64_t *bisected, Keep &keep) {
#ifdef BISECT_SCAN_AVX2
  if (testing::vector_scan())
    return scan_flagged_avx2<N>(cells, lo, hi, flag, bisected, keep);
#endif
  scan_flagged_scalar<N>(cells, lo, hi, flag, bisected, keep);
}

// Open-addressing map from an edge key (min << 32 | max, never 0) to the id
// of its midpoint.
class MidpointMap {
public:
  static std::uint64_t key(VertexId a, VertexId b) {
    if (a > b)
      std::swap(a, b);
    return std::uint64_t(a) << 32 | b;
  }
  // A filter in front of find(): one bit per key, at a hash of it (a Bloom
  // filter with one hash function), for about `n` keys. Most edges find() is
  // asked about have no midpoint, and the filter, small enough to stay in
  // cache, answers for most of them without a probe of the table (3D ball,
  // 12 iterations, 8.8 M candidate cells, one thread, refine() timed in an
  // in-process harness: 1.65-1.85 s without it, 1.33-1.58 s with it, runs
  // alternated on a noisy machine). At most 4 MB (kFilterBits): a larger
  // one, read at random while the closure's scan streams the cells through
  // the cache, missed it more often than the false positives of a smaller
  // one cost (Gmsh's 49,090-tet ball, 14 iterations, one thread, whose
  // last iterations of 10.8 and 18.3 M tets had 8 and 16 MB: refinement
  // 12.1-12.9 s against 11.0-12.0 with 4 MB in three runs alternated;
  // 2 MB or 1 MB were not better).
  static constexpr std::size_t kFilterBits = std::size_t(1) << 25;
  void expect(std::size_t n) {
    std::size_t bits = std::size_t(1) << 16;
    while (bits < 4 * n && bits < kFilterBits)
      bits *= 2;
    filter_.assign(bits / 64, 0);
    filter_mask_ = bits - 1;
  }
  // Room for `keys` keys before the first insert, so that the serial
  // kernel's insert() does not grow the table from 1024 slots by doubling
  // (each step a fresh table and a rehash: Gmsh's 3D ball, 14 iterations,
  // one thread, about 0.5 GB asked for in tables whose largest was 134 MB).
  void presize(std::size_t keys) {
    if (size_ == 0 && 2 * (keys + 1) > capacity_)
      grow(2 * (keys + 1));
  }
  VertexId find(std::uint64_t k) const {
    if (size_ == 0)
      return kNoVertex;
    if (!filter_.empty()) {
      const std::size_t h = filter_bit(k);
      if (!(filter_[h >> 6] >> (h & 63) & 1))
        return kNoVertex;
    }
    for (std::size_t i = slot(k);; i = (i + 1) & mask_) {
      if (slots_[i].key == k)
        return slots_[i].value;
      if (slots_[i].key == 0)
        return kNoVertex;
    }
  }
  // Returns the slot's value, inserting `value` when k is absent.
  VertexId insert(std::uint64_t k, VertexId value) {
    if ((keys_ + 1) * 2 > capacity_)
      grow();
    for (std::size_t i = slot(k);; i = (i + 1) & mask_) {
      Slot &e = slots_[i];
      if (e.key == k)
        return e.value;
      if (e.key == 0) {
        e.key = k;
        e.value = value;
        ++size_;
        ++keys_;
        if (!filter_.empty()) {
          const std::size_t h = filter_bit(k);
          filter_[h >> 6] |= std::uint64_t(1) << (h & 63);
        }
        return value;
      }
    }
  }
  // The parallel kernel's side (Refiner::bisect_all). A round of `more`
  // claims inserts at most `more` keys but usually far fewer (a new edge is
  // bisected by every cell of the pass around it: 3D ball, 12 iterations,
  // the last made 238,000 midpoints for 529,000 selected cells), so room is made for half of them
  // at a load of 0.6, and claim() stops inserting at 3/4 of the slots; the round then finds
  // overflowed() set, grows the table and claims again. The table is never
  // full, so every probe ends. Room for all `more` at a load of 1/2 made
  // the last iteration's table 4 times the size the serial kernel's
  // reaches (3D ball, 12 iterations: 32 MB, a tenth of the peak memory).
  static constexpr std::uint32_t kNoSlot = std::uint32_t(-1);
  void begin_round(std::size_t more) {
    const int room = testing::midpoint_room();
    more = room > 0 ? more / std::size_t(room) : more / 2;
    if (capacity_ == 0 || 10 * (keys_ + more) > 6 * capacity_)
      grow((10 * (keys_ + more) + 5) / 6);
    limit_ = capacity_ / 4 * 3;
    overflow_ = false;
  }
  bool overflowed() const { return overflow_; }
  // After an overflow: a larger table holding the keys claimed (their bids
  // forgotten), for the round to claim again.
  void retry_round(std::size_t more) {
    testing::count_midpoint_retry();
    grow();
    begin_round(more);
  }
  // The slot of key k, which the calling thread inserts when no thread has:
  // safe from several threads at once, between begin_round() and settle().
  // kNoSlot once the round has overflowed. `credits` (the thread's, 0 at
  // first) are keys it may insert, taken from the shared count in batches.
  std::uint32_t claim(std::uint64_t k, std::size_t &credits) {
    std::atomic_ref<bool> overflow(overflow_);
    if (overflow.load(std::memory_order_relaxed))
      return kNoSlot;
    const std::uint32_t s = claim_slot(k, credits);
    if (s != kNoSlot)
      return s;
    overflow.store(true, std::memory_order_relaxed);
    return kNoSlot;
  }
  // A slot claimed in this round has no value yet; `who` (an index into the
  // round's work) bids to be its first claimant, the smallest index wins.
  // Returns whether `who` was the smallest bidder when it bid: false means
  // it has lost; true, that it may win, unless a smaller index bids later.
  bool fresh(std::uint32_t s) const { return slots_[s].value == kNoVertex; }
  bool bid(std::uint32_t s, std::uint32_t who) {
    std::atomic_ref<std::uint32_t> f(slots_[s].first);
    std::uint32_t seen = f.load(std::memory_order_relaxed);
    while (who < seen)
      if (f.compare_exchange_weak(seen, who, std::memory_order_relaxed))
        return true;
    return seen == who;
  }
  std::uint32_t first_bidder(std::uint32_t s) const { return slots_[s].first; }
  // Asks for slot s ahead of fresh(), first_bidder(), settle() or value().
  void prefetch_slot(std::uint32_t s) const { __builtin_prefetch(&slots_[s]); }
  // Asks for what insert(k) or claim(k) reads first, ahead of it.
  void prefetch_key(std::uint64_t k) const {
    if (capacity_ != 0)
      __builtin_prefetch(&slots_[slot(k)]);
  }
  // Reads what insert(k) reads first (its slot, and the filter's word it
  // sets when k is new); the value means nothing (Refiner::touch_bisection).
  std::uint64_t touch_key(std::uint64_t k) const {
    std::uint64_t t = capacity_ != 0 ? slots_[slot(k)].key : 0;
    if (!filter_.empty())
      t ^= filter_[filter_bit(k) >> 6];
    return t;
  }
  // Gives a fresh slot its value (one thread per slot).
  void settle(std::uint32_t s, VertexId value) {
    slots_[s].value = value;
    slots_[s].first = kNobody;
    if (!filter_.empty()) {
      const std::size_t h = filter_bit(slots_[s].key);
      std::atomic_ref<std::uint64_t>(filter_[h >> 6])
          .fetch_or(std::uint64_t(1) << (h & 63), std::memory_order_relaxed);
    }
  }
  VertexId value(std::uint32_t s) const { return slots_[s].value; }
  // The end of a round that made n new midpoints (one per key it inserted).
  void end_round(std::size_t n) {
    size_ += n;
    keys_ = size_;
  }

private:
  static constexpr std::uint32_t kNobody = std::uint32_t(-1);
  // Key and value side by side: a probe that finds its key reads one cache
  // line. `first` serves the parallel kernel's bids (kNobody between rounds).
  struct Slot {
    std::uint64_t key; // 0: empty
    VertexId value;
    std::uint32_t first;
  };
  // claim()'s probe; kNoSlot when inserting k would take the keys, with
  // every thread's unused credits, past limit_.
  std::uint32_t claim_slot(std::uint64_t k, std::size_t &credits) {
    constexpr std::size_t kBatch = 256;
    for (std::size_t i = slot(k);; i = (i + 1) & mask_) {
      std::atomic_ref<std::uint64_t> key(slots_[i].key);
      std::uint64_t seen = key.load(std::memory_order_acquire);
      if (seen == 0) {
        if (credits == 0) {
          std::atomic_ref<std::size_t> keys(keys_);
          if (keys.fetch_add(kBatch, std::memory_order_relaxed) + kBatch > limit_)
            return kNoSlot;
          credits = kBatch;
        }
        if (key.compare_exchange_strong(seen, k, std::memory_order_acq_rel)) {
          --credits;
          return std::uint32_t(i);
        }
      }
      if (seen == k)
        return std::uint32_t(i);
    }
  }
  std::size_t slot(std::uint64_t k) const {
    return std::size_t((k * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
  }
  std::size_t filter_bit(std::uint64_t k) const {
    return std::size_t((k * 0xC2B2AE3D27D4EB4Full) >> 24) & filter_mask_;
  }
  // Twice the slots, or the next power of two from there that holds
  // `at_least`, filled and rehashed by all threads when it is large (the
  // tables of the last iterations are; filling and rehashing them on one
  // thread was a tenth of the refinement on two). The keys are distinct, so
  // where each lands does not depend on the threads, and the filter already
  // holds them.
  void grow(std::size_t at_least = 0) {
    std::unique_ptr<Slot[]> old = std::move(slots_);
    const std::size_t old_capacity = capacity_;
    capacity_ = std::max<std::size_t>(1024, 2 * old_capacity);
    while (capacity_ < at_least)
      capacity_ *= 2;
    mask_ = capacity_ - 1;
    slots_ = std::make_unique_for_overwrite<Slot[]>(capacity_);
    const int workers = capacity_ >= (std::size_t(1) << 16) ? threads() : 1;
    std::size_t keys = 0;
#pragma omp parallel num_threads(workers)
    {
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < capacity_; ++i)
        slots_[i] = Slot{0, kNoVertex, kNobody};
#pragma omp for schedule(static) reduction(+ : keys)
      for (std::size_t j = 0; j < old_capacity; ++j)
        if (old[j].key) {
          slots_[rehash(old[j].key)].value = old[j].value;
          ++keys;
        }
    }
    keys_ = keys; // without a failed round's unused credits
  }
  // grow()'s insert of a key known to be absent.
  std::uint32_t rehash(std::uint64_t k) {
    for (std::size_t i = slot(k);; i = (i + 1) & mask_) {
      std::atomic_ref<std::uint64_t> key(slots_[i].key);
      std::uint64_t seen = 0;
      if (key.load(std::memory_order_relaxed) == 0 &&
          key.compare_exchange_strong(seen, k, std::memory_order_relaxed))
        return std::uint32_t(i);
    }
  }
  std::unique_ptr<Slot[]> slots_;
  std::size_t capacity_ = 0;
  std::size_t keys_ = 0;  // slots with a key: size_ and the claims of a round
  std::size_t limit_ = 0; // claim() inserts no key past this many
  bool overflow_ = false;
  std::vector<std::uint64_t> filter_; // expect()
  std::size_t filter_mask_ = 0;
  std::size_t size_ = 0, mask_ = 0;
};

// The cells around a vertex during one refine() call, for the closure's
// passes that make few midpoints (Refiner::walk_around): the input cells
// around each input vertex, and each input cell's descendants appended so
// far, newest first. A bisection keeps each vertex of its cell in one child
// or both and adds only the midpoint, so a cell holding an input vertex
// descends from an input cell holding it; a cell holding a vertex the call
// made descends from a cell holding that vertex's edge, so from an input
// cell holding the root of its edge's first end (Refiner::root).
// Memory: 4 (d + 1) bytes per input cell and 4 per input vertex for the
// cells around, 4 per input cell and 4 per appended cell for the
// descendants.
template <int N> class Around {
public:
  bool built() const { return !start_.empty(); }
  // Over the cells [0, nc0) of `cells` and the vertices [0, nv0); nc0 * N
  // must be below kNoCell. A vertex's range is its cells in increasing
  // order, whatever the number of threads. A counting sort in two steps,
  // so that no step writes at random over the whole array: the ids go
  // first to their vertex's bucket (a range of 2^shift vertices, at most
  // about kBuckets buckets), each bucket filled in cell order by a few
  // hundred streams, with the vertex's place in its bucket beside each (2
  // bytes); then each bucket is counted and sorted by vertex on its own,
  // in a thread's cache. One step writing every id straight to its vertex's
  // place (before 2026-12-05) wrote at random over 16 bytes per input cell:
  // 3D ball, 15 iterations, one thread: 4.8 s of the refinement's 28.6 in
  // building these lists, 3.2 s for the last iteration's 31 M input tets.
  // Memory while building: 2 bytes per slot (8 per input tet) and a
  // bucket's ids per thread.
  void build(const VertexId *cells, std::size_t nc0, std::size_t nv0, int workers) {
    const std::size_t slots = nc0 * N;
    start_.assign(nv0 + 1, 0);
    around_ = std::make_unique_for_overwrite<CellId[]>(slots);
    int shift = 0;
    while (shift < 16 && (nv0 >> shift) >= kBuckets)
      ++shift;
    const std::size_t nb = (nv0 >> shift) + 1;
    const int w = std::clamp(workers, 1, kBuildWorkers);
    // at[t * nb + b]: thread t's ids in bucket b, then where its next goes.
    std::vector<std::size_t> at(std::size_t(w) * nb, 0), bucket(nb + 1, 0);
    const auto low = std::make_unique_for_overwrite<std::uint16_t[]>(slots);
    const std::uint32_t mask = (std::uint32_t(1) << shift) - 1;
    std::uint32_t *start = start_.data();
    CellId *around = around_.get();
    std::uint16_t *place = low.get();
    // No descendants yet: filled by all threads, which a vector's assign()
    // did on one, in fresh pages.
    first_ = std::make_unique_for_overwrite<CellId[]>(nc0);
    CellId *first = first_.get();
#pragma omp parallel num_threads(w)
    {
      const std::size_t t = std::size_t(omp_get_thread_num()),
                        n = std::size_t(omp_get_num_threads());
      std::size_t *mine = at.data() + t * nb;
      const std::size_t c0 = nc0 * t / n, c1 = nc0 * (t + 1) / n;
      std::fill(first + c0, first + c1, kNoCell);
      for (std::size_t s = c0 * N; s < c1 * N; ++s)
        ++mine[cells[s] >> shift];
#pragma omp barrier
#pragma omp single
      {
        std::size_t sum = 0;
        for (std::size_t b = 0; b < nb; ++b) {
          bucket[b] = sum;
          for (std::size_t u = 0; u < n; ++u) {
            const std::size_t k = at[u * nb + b];
            at[u * nb + b] = sum;
            sum += k;
          }
        }
        bucket[nb] = sum;
      }
      for (std::size_t c = c0; c < c1; ++c)
        for (int i = 0; i < N; ++i) {
          const VertexId v = cells[c * N + std::size_t(i)];
          const std::size_t p = mine[v >> shift]++;
          around[p] = CellId(c);
          place[p] = std::uint16_t(v & mask);
        }
#pragma omp barrier
      std::vector<std::uint32_t> count(std::size_t(mask) + 2);
      std::vector<CellId> sorted;
#pragma omp for schedule(dynamic, 4)
      for (std::size_t b = 0; b < nb; ++b) {
        const std::size_t b0 = bucket[b], b1 = bucket[b + 1];
        const std::size_t v0 = b << shift, v1 = std::min(nv0, (b + 1) << shift);
        if (v0 >= v1)
          continue;
        std::fill(count.begin(), count.end(), 0u);
        for (std::size_t p = b0; p < b1; ++p)
          ++count[place[p] + 1u];
        // count[k + 1] is vertex v0 + k's number of cells: count[k] becomes
        // the place of its first one in the bucket.
        std::uint32_t sum = 0;
        for (std::size_t v = v0; v < v1; ++v) {
          sum += count[v - v0];
          count[v - v0] = sum;
          start[v] = std::uint32_t(b0) + sum;
        }
        sorted.resize(b1 - b0);
        for (std::size_t p = b0; p < b1; ++p)
          sorted[count[place[p]]++] = around[p];
        std::copy(sorted.begin(), sorted.end(), around + b0);
      }
    }
    start[nv0] = std::uint32_t(slots);
    next_.clear();
    nc0_ = nc0;
  }
  std::size_t count(VertexId v) const {
    return start_[v + 1] - start_[v];
  }
  // Room for the descendants of `cells` cells in all (the input's and the
  // appended ones), made once when the cell arrays grow rather than by
  // doubling, which kept a copy alive.
  void expect(std::size_t cells) {
    if (cells > nc0_ && next_.capacity() < cells - nc0_)
      next_.reserve(cells - nc0_);
  }
  // Cell c, appended, descends from input cell `input`; cells are adopted
  // in the order they were appended.
  void adopt(CellId c, CellId input) {
    next_.push_back(first_[input]);
    first_[input] = c;
  }
  // f(c) for the input cells around input vertex v and their descendants.
  template <class F> void for_each(VertexId v, F &&f) const {
    for (std::uint32_t i = start_[v]; i < start_[v + 1]; ++i) {
      const CellId o = around_[i];
      f(o);
      for (CellId d = first_[o]; d != kNoCell; d = next_[d - nc0_])
        f(d);
    }
  }

private:
  std::vector<std::uint32_t> start_; // per input vertex, and one past: its range in around_
  static constexpr int kBuildWorkers = 8;
  static constexpr std::size_t kBuckets = 1024;
  std::unique_ptr<CellId[]> around_;
  std::unique_ptr<CellId[]> first_; // per input cell: its newest appended descendant
  std::vector<CellId> next_;        // per appended cell: the next older one of its input cell
  std::size_t nc0_ = 0;
};

struct LimitReached {};
struct PrecisionReached {};
struct Cancelled {};

template <int Dim> class Refiner {
  static constexpr int N = Dim + 1;

public:
  Refiner(Mesh &mesh, const RefineLimits &limits)
      : m_(mesh), order_(edge_order(mesh)), limits_(limits), nc0_(mesh.num_cells()),
        nv0_(mesh.num_vertices()), endpoint_((mesh.num_vertices() + 63) / 64, 0) {
    // The tree (mesh.hpp): a mesh without one starts a sequence here.
    if (!m_.has_tree()) {
      m_.generation.assign(nc0_, 0);
      m_.parent_edge.assign(2 * nv0_, kNoVertex);
    }
    // This call's vertices are one level newer than the newest so far.
    if (m_.level.size() != nv0_) {
      m_.level.assign(nv0_, 0);
      for (std::size_t v = 0; v < nv0_; ++v)
        if (m_.parent_edge[2 * v] != kNoVertex)
          m_.level[v] = 1;
    }
    const std::uint16_t newest =
        m_.level.empty() ? 0 : *std::max_element(m_.level.begin(), m_.level.end());
    level_ =
        newest == std::numeric_limits<std::uint16_t>::max() ? newest : std::uint16_t(newest + 1);
    // The undo log costs memory and keeps the kernel serial: keep it only
    // when a limit could trip: the caller's, or the 32-bit ids' for a mesh
    // that one call could take past them, taken as a mesh within 16 times
    // its cells of them (an iteration about doubles the cells it touches;
    // 16 is a margin, not a proven bound: past it without the log, reserve()
    // throws before anything is written).
    logging_ = limits.max_cells != std::numeric_limits<std::size_t>::max() ||
               17 * nc0_ >= kNoCell - 1 || nv0_ + 16 * nc0_ >= limits.max_vertices || limits.cancel;
    limits_.max_cells = std::min<std::size_t>(limits.max_cells, kNoCell - 1);
    // Tagged entities split with their cells; a mesh without any has no
    // splitter, and the kernel's only cost is testing the null pointer.
    if (!m_.entities.empty())
      splitter_ = std::make_unique<EntitySplitter>(m_);
    mids_.expect(nc0_);
  }

  RefineResult run(std::vector<CellId> work,
                   const std::vector<std::array<VertexId, 2>> &split = {}) {
    RefineResult result;
    result.selected = work.size();
    if (limits_.origin)
      limits_.origin->clear();
    // Closure bisects cells about as coarse as the selected ones or coarser;
    // when a selected cell's edge is near the precision limit, keep the undo
    // log so that passing it anywhere undoes the iteration. (On all threads:
    // each cell's edge ends are read at random.)
    if (!logging_) {
      int near = 0;
      const std::size_t n = work.size();
      const int workers = n >= kParallelPass ? threads() : 1;
#pragma omp parallel for num_threads(workers) schedule(static) reduction(max : near)
      for (std::size_t i = 0; i < n; ++i)
        near = std::max(near, int(resolution(refinement_edge(work[i])) < 1024));
      logging_ = near != 0;
    }
    if (logging_ && splitter_)
      entities0_ = m_.entities; // what undo() puts back
    if (logging_)
      logged_.assign((nc0_ + 63) / 64, 0);
    try {
      std::vector<std::uint64_t> flag;     // per vertex: an end of an edge bisected in this pass
      std::vector<std::uint64_t> bisected; // per cell: bisected in this pass
      std::vector<std::uint64_t> seen;     // per cell: found by walk_around() in this pass
      std::vector<std::vector<CellId>> found;
      if (!split.empty())
        add_split_edges(split, work, found);
      const int walk = testing::walk_around();
      // Nothing to bisect (a region that selects nothing): nothing to walk.
      if (!work.empty() && walk >= 0 && ((Dim == 3 && nc0_ >= kAroundFrom) || walk > 0) &&
          nc0_ * N < kNoCell)
        around_.build(m_.cells.data(), nc0_, nv0_, threads());
      // Room for the whole iteration at once, about: see reserve().
      reserve(work.size(), 3 * work.size());
      // The call's midpoints, about: per selected cell 0.95 in 2D, 0.42-0.46
      // in 3D and 0.08-0.13 in 4D in the benchmarks' larger iterations
      // (bench/e2e.sh); fewer than that leaves room, more grow the table
      // once or twice as before.
      mids_.presize(Dim == 2 ? work.size() : Dim == 3 ? work.size() * 9 / 20 : work.size() / 8);
      while (!work.empty()) {
        if (limits_.cancel && limits_.cancel->load())
          throw Cancelled{};
        const std::size_t cells_before = m_.num_cells(), verts_before = m_.num_vertices();
        reserve(work.size(), work.size());
        const auto t0 = std::chrono::steady_clock::now();
        if (parallel_round(work.size()))
          bisect_all(work);
        else
          for (std::size_t i0 = 0; i0 < work.size(); i0 += kBisectBatch) {
            const std::size_t i1 = std::min(work.size(), i0 + kBisectBatch);
            std::uint64_t t = 0;
            for (std::size_t i = i0; i < i1; ++i)
              t ^= touch_bisection(work[i]);
            asm volatile("" ::"r"(t)); // the reads happen
            for (std::size_t i = i0; i < i1; ++i)
              bisect(work[i]);
          }
        result.kernel_seconds +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        result.bisections += work.size();
        // The next pass: the cells with a bisected edge among those that can
        // have one, the cells just bisected (in their first child's slot),
        // the children just made, and every cell holding both ends of an
        // edge bisected in this pass (ALGORITHMS §6), in cell order, so the
        // order does not depend on the threads or on how they were found.
        // The bits set here (bisected, flag, seen) are cleared again by the
        // pass, so that no pass costs more than its work and what it reads.
        bisected.resize(std::max(bisected.size(), (cells_before + 63) / 64), 0);
        for (CellId c : work)
          bisected[c >> 6] |= std::uint64_t(1) << (c & 63);
        if (m_.num_vertices() > verts_before && walk_pays(verts_before, cells_before)) {
          found.resize(1);
          walk_around(verts_before, cells_before, work, bisected, seen, found[0]);
          testing::count_walk();
        } else if (m_.num_vertices() > verts_before) {
          // Every cell is read, one test per block of cells on all threads;
          // nothing serial but marking the pass's cells and the ends of its
          // edges (the candidates were gathered and deduplicated on one
          // thread: 3D ball, two threads, a twentieth of refine).
          // A bit per vertex: the scan below reads it for every cell of
          // every pass, and bits stay in cache where bytes did not (3D
          // ball, 12 iterations, 125 M cells scanned: 0.46 -> 0.37 s).
          flag.resize(std::max(flag.size(), (m_.num_vertices() + 63) / 64), 0);
          for_each_new_end(verts_before,
                           [&flag](VertexId a) { flag[a >> 6] |= std::uint64_t(1) << (a & 63); });
          const VertexId *cells = m_.cells.data();
          const std::uint64_t *ends_flag = flag.data(), *was_bisected = bisected.data();
          for_block_ranges(
              cells_before, found,
              [this, cells, ends_flag, was_bisected](std::size_t lo, std::size_t hi,
                                                     std::vector<CellId> &out) {
                Hanging test(*this, out);
                auto keep = [&test, cells, was_bisected](std::size_t c, unsigned ends) {
                  // A cell this pass did not bisect had no bisected edge before
                  // it (else the pass would have bisected it): only an edge
                  // with both ends flagged can have a midpoint.
                  test.add(CellId(c), cells + c * N,
                           was_bisected[c >> 6] >> (c & 63) & 1 ? Hanging::kAnyEnds : ends);
                };
                scan_flagged<N>(cells, lo, hi, ends_flag, was_bisected, keep);
                test.flush();
              });
          for_each_new_end(verts_before, [&flag](VertexId a) { flag[a >> 6] = 0; });
        } else {
          // No new midpoint: no cell but these has a new bisected edge.
          const VertexId *cells = m_.cells.data();
          for_block_ranges(
              work.size(), found,
              [this, cells, &work](std::size_t lo, std::size_t hi, std::vector<CellId> &out) {
                Hanging test(*this, out);
                for (std::size_t i = lo; i < hi; ++i)
                  test.add(CellId(i), cells + std::size_t(work[i]) * N, Hanging::kAnyEnds);
                test.flush();
              });
          for (std::vector<CellId> &block : found)
            for (CellId &i : block)
              i = work[i];
        }
        for (CellId c : work)
          bisected[c >> 6] = 0;
        work.clear();
        if (around_.built()) {
          around_.expect(m_.cells.capacity() / N);
          for (std::size_t c = cells_before; c < m_.num_cells(); ++c)
            around_.adopt(CellId(c), origin_[c - nc0_]);
        }
        for (const std::vector<CellId> &block : found)
          work.insert(work.end(), block.begin(), block.end());
        const VertexId *children = m_.cells.data() + cells_before * N;
        for_block_ranges(
            m_.num_cells() - cells_before, found,
            [this, children](std::size_t lo, std::size_t hi, std::vector<CellId> &out) {
              Hanging test(*this, out);
              for (std::size_t i = lo; i < hi; ++i)
                test.add(CellId(i), children + i * N, Hanging::kAnyEnds);
              test.flush();
            });
        for (const std::vector<CellId> &block : found)
          for (CellId i : block)
            work.push_back(CellId(cells_before + i));
        if (!work.empty())
          ++result.closure_passes;
      }
    } catch (const LimitReached &) {
      undo();
      result.limit_reached = true;
      return result;
    } catch (const PrecisionReached &) {
      undo();
      result.limit_reached = result.precision_reached = true;
      return result;
    } catch (const Cancelled &) {
      undo();
      result.cancelled = true;
      return result;
    }
    finish();
    if (limits_.origin)
      *limits_.origin = std::move(origin_);
    return result;
  }

private:
  // The edges a caller asks to have bisected (refine with `split`): each one
  // some cell holds gets its midpoint now, and every cell holding it joins
  // the first pass (once, also when selected): bisected by its own edge,
  // its children keep the hanging midpoint until the closure reaches it.
  void add_split_edges(const std::vector<std::array<VertexId, 2>> &split, std::vector<CellId> &work,
                       std::vector<std::vector<CellId>> &found) {
    std::vector<std::uint64_t> keys;
    keys.reserve(split.size());
    std::vector<std::uint8_t> end(m_.num_vertices(), 0);
    for (const std::array<VertexId, 2> &e : split) {
      if (e[0] == e[1] || e[0] >= m_.num_vertices() || e[1] >= m_.num_vertices())
        throw CheckError("refine: an edge to split names a vertex the mesh does not have");
      keys.push_back(MidpointMap::key(e[0], e[1]));
      end[e[0]] = end[e[1]] = 1;
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    auto wanted = [&](VertexId a, VertexId b) {
      return end[a] && end[b] &&
             std::binary_search(keys.begin(), keys.end(), MidpointMap::key(a, b));
    };
    for_blocks(m_.num_cells(), found, [&](std::size_t c) {
      const VertexId *x = m_.cell(CellId(c));
      for (const LocalEdge &e : kLocalEdges<Dim>)
        if (wanted(x[e.first], x[e.second]))
          return true;
      return false;
    });
    std::vector<std::uint64_t> in((m_.num_cells() + 63) / 64, 0);
    for (CellId c : work)
      in[c >> 6] |= std::uint64_t(1) << (c & 63);
    for (const std::vector<CellId> &block : found)
      for (CellId c : block) {
        const VertexId *x = m_.cell(c);
        for (const LocalEdge &e : kLocalEdges<Dim>)
          if (wanted(x[e.first], x[e.second]))
            midpoint(x[e.first], x[e.second]);
        if (!(in[c >> 6] >> (c & 63) & 1)) {
          in[c >> 6] |= std::uint64_t(1) << (c & 63);
          work.push_back(c);
        }
      }
  }

  // Calls f(a) for both ends of the edge of every vertex made since
  // vertex `from`.
  template <class F> void for_each_new_end(std::size_t from, F &&f) const {
    for (std::size_t v = from; v < m_.num_vertices(); ++v) {
      f(m_.parent_edge[2 * v]);
      f(m_.parent_edge[2 * v + 1]);
    }
  }

  // An input vertex such that every cell holding v descends from an input
  // cell around it (Around): v itself for an input vertex, else the root of
  // the first end of v's edge.
  VertexId root(VertexId v) const {
    while (v >= nv0_)
      v = m_.parent_edge[2 * std::size_t(v)];
    return v;
  }
  // Of the edge (a, b)'s two roots, the one with fewer input cells around.
  VertexId fewer_around(VertexId a, VertexId b) const {
    const VertexId ra = root(a), rb = root(b);
    return around_.count(ra) <= around_.count(rb) ? ra : rb;
  }

  // Whether walk_around() should find the next pass's cells rather than a
  // scan of every cell: when the cells it reads, about (the input cells
  // around the edges' roots and as many descendants each as the input
  // cells have on average), cost less than the scan's cells_before. One
  // cell read by the walk was taken to cost kWalkCost cells scanned.
  bool walk_pays(std::size_t verts_before, std::size_t cells_before) const {
    if (!around_.built())
      return false;
    if (testing::walk_around() > 0)
      return true;
    const std::size_t budget = cells_before / kWalkCost;
    const double per_input = double(m_.num_cells()) / double(nc0_);
    double reads = 0;
    for (std::size_t v = verts_before; v < m_.num_vertices(); ++v) {
      reads +=
          per_input *
          double(around_.count(fewer_around(m_.parent_edge[2 * v], m_.parent_edge[2 * v + 1])));
      if (reads > double(budget))
        return false;
    }
    return true;
  }

  // The next pass's cells among [0, cells_before) (run()), without a scan:
  // the cells bisected in this pass that still have a bisected edge, and
  // each other cell holding both ends of an edge bisected in this pass,
  // looked for among the descendants of the input cells around one root
  // of the edge. `bisected` marks the pass's cells; `seen` is clear and is
  // left clear. out: in increasing order, as the scan finds them.
  void walk_around(std::size_t verts_before, std::size_t cells_before,
                   const std::vector<CellId> &work, const std::vector<std::uint64_t> &bisected,
                   std::vector<std::uint64_t> &seen, std::vector<CellId> &out) const {
    out.clear();
    seen.resize(std::max(seen.size(), (cells_before + 63) / 64), 0);
    const VertexId *cells = m_.cells.data();
    // The edges on all threads, a share each. A cell around two edges is
    // kept by the thread that sets its bit in `seen` first: which cells are
    // found does not depend on the threads, and they are sorted below.
    // (Gmsh's 3D ball, 14 iterations, two threads, three runs each
    // alternated: the walks took 0.31-0.46 s on one thread, 0.24-0.26 s.)
    const std::size_t v0 = verts_before, v1 = m_.num_vertices();
    const int workers = v1 - v0 >= kParallelWalk ? threads() : 1;
    std::vector<std::vector<CellId>> part(static_cast<std::size_t>(workers));
#pragma omp parallel num_threads(workers)
    {
      std::vector<CellId> &mine = part[std::size_t(omp_get_thread_num())];
#pragma omp for schedule(dynamic, 64)
      for (std::size_t v = v0; v < v1; ++v) {
        const VertexId a = m_.parent_edge[2 * v], b = m_.parent_edge[2 * v + 1];
        around_.for_each(fewer_around(a, b), [&](CellId d) {
          const std::uint64_t bit = std::uint64_t(1) << (d & 63);
          if (d >= cells_before || (bisected[d >> 6] & bit))
            return;
          std::atomic_ref<std::uint64_t> word(seen[d >> 6]);
          if (word.load(std::memory_order_relaxed) & bit)
            return;
          const VertexId *x = cells + std::size_t(d) * N;
          bool has_a = false, has_b = false;
          for (int i = 0; i < N; ++i) {
            has_a |= x[i] == a;
            has_b |= x[i] == b;
          }
          if (has_a && has_b && !(word.fetch_or(bit, std::memory_order_relaxed) & bit))
            mine.push_back(d);
        });
      }
    }
    for (const std::vector<CellId> &p : part)
      out.insert(out.end(), p.begin(), p.end());
    for (CellId c : out)
      seen[c >> 6] = 0;
    Hanging test(*this, out);
    for (CellId c : work)
      test.add(c, cells + std::size_t(c) * N, Hanging::kAnyEnds);
    test.flush();
    std::sort(out.begin(), out.end());
  }

  // found[k] = the indices i in block k of [0, n) (blocks of kBlock) for
  // which test(i) holds, in increasing order; blocks are tested by all
  // threads when there are enough of them.
  template <class Test>
  static void for_blocks(std::size_t n, std::vector<std::vector<CellId>> &found, Test &&test) {
    for_block_ranges(n, found,
                     [test](std::size_t lo, std::size_t hi, std::vector<CellId> &out) mutable {
                       for (std::size_t i = lo; i < hi; ++i)
                         if (test(i))
                           out.push_back(CellId(i));
                     });
  }
  // The same with scan(lo, hi, out) appending to out (empty) what block
  // [lo, hi) finds, in increasing order; lo is a multiple of kBlock.
  template <class Scan>
  static void for_block_ranges(std::size_t n, std::vector<std::vector<CellId>> &found,
                               Scan &&scan) {
    constexpr std::size_t kBlock = std::size_t(1) << 14;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    found.resize(blocks);
    const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (std::size_t k = 0; k < blocks; ++k) {
      // A copy of the scan on this thread's stack: what it holds stays in
      // registers across the push_back()s (a scan of every cell per pass
      // reloaded the mesh's pointers for every cell).
      std::remove_cvref_t<Scan> local = scan;
      std::vector<CellId> &out = found[k];
      out.clear();
      local(k * kBlock, std::min(n, (k + 1) * kBlock), out);
    }
  }

  // The local indices of cell c's refinement edge: (0, tag) in a Maubach
  // cell, the consistent edge of the old sub-simplex in Stage 1 (x = its new
  // vertices, then the old sub-simplex).
  EdgePick refinement_pick(CellId c) const {
    if (m_.stage[c] == Stage::Maubach)
      return {0, m_.tag[c]};
    return opposite_edge(order_, m_.cell(c), Dim, m_.tag[c]);
  }
  std::pair<VertexId, VertexId> refinement_edge(CellId c) const {
    const EdgePick e = refinement_pick(c);
    return {m_.cell(c)[e.first], m_.cell(c)[e.second]};
  }

  // The edge's extent over the smallest extent it may have to be bisected
  // (kRelativeResolution, kAbsoluteResolution): below 1 it must not be.
  double resolution(std::pair<VertexId, VertexId> edge) const {
    const double *p = m_.point(edge.first), *q = m_.point(edge.second);
    double extent = 0, magnitude = 0;
    for (int k = 0; k < Dim; ++k) {
      extent = std::max(extent, std::abs(p[k] - q[k]));
      magnitude = std::max({magnitude, std::abs(p[k]), std::abs(q[k])});
    }
    return extent / std::max(kRelativeResolution * magnitude, kAbsoluteResolution);
  }

  // The cell's vertices that are an end of an edge bisected in this call
  // (bit i: x[i]).
  unsigned bisected_ends(const VertexId *x) const {
    const std::uint64_t *endpoint = endpoint_.data();
    unsigned ends = 0;
    for (int i = 0; i < N; ++i)
      ends |= unsigned(endpoint[x[i] >> 6] >> (x[i] & 63) & 1) << i;
    return ends;
  }
  // Whether an edge of x between two vertices of the set `ends` (bit i:
  // x[i]) has a midpoint: the pairs of set bits, without a table of edges
  // (ends has two or three bits set, or none, in most cells asked).
  bool has_midpoint_among(const VertexId *x, unsigned ends) const {
    for (unsigned a = ends; a & (a - 1); a &= a - 1) {
      const VertexId p = x[std::countr_zero(a)];
      for (unsigned b = a & (a - 1); b; b &= b - 1)
        if (mids_.find(MidpointMap::key(p, x[std::countr_zero(b)])) != kNoVertex)
          return true;
    }
    return false;
  }

  // The closure's test of which cells have a bisected edge, for cells given
  // in increasing order: add(c, x, ends) asks whether an edge of the cell x
  // between two vertices of `ends` has a midpoint (kAnyEnds: any edge, as
  // for a cell bisected in this pass or just made), and flush() appends
  // the cells for which one has to `out`, in the order added. The answers
  // are taken kBatch cells at a time, in a loop that does nothing else:
  // each reads the midpoint table's filter and often a slot of the table
  // at random, and there the reads of several cells wait for memory
  // together, where in the scan's loop (between its own reads and
  // branches) they waited one after the other. 3D ball, Gmsh's 49,090
  // tets, 14 iterations, one thread: the first pass of the last iteration
  // asked about 10.2 M of its 18.3 M cells (10.8 M pairs of ends, 2.2 M
  // with a midpoint); its scan took 0.84-0.99 s one cell at a time and
  // 0.65-0.91 s in batches. Whole refinement, 13 iterations, five runs
  // each alternated on a noisy machine: best 7.19 s against 6.49.
  // Prefetching each batch's filter words and slots before the answers,
  // or a pipeline of prefetches 8 cells ahead, saved nothing more.
  class Hanging {
  public:
    static constexpr unsigned kAnyEnds = ~0u;
    Hanging(const Refiner &r, std::vector<CellId> &out) : r_(r), out_(out) {}
    void add(CellId c, const VertexId *x, unsigned ends) {
      id_[n_] = c;
      x_[n_] = x;
      ends_[n_] = ends;
      if (++n_ == kBatch)
        flush();
    }
    void flush() {
      for (int i = 0; i < n_; ++i)
        if (ends_[i] == kAnyEnds)
          ends_[i] = r_.bisected_ends(x_[i]);
      for (int i = 0; i < n_; ++i)
        if (r_.has_midpoint_among(x_[i], ends_[i]))
          out_.push_back(id_[i]);
      n_ = 0;
    }

  private:
    static constexpr int kBatch = 32;
    const Refiner &r_;
    std::vector<CellId> &out_;
    int n_ = 0;
    CellId id_[kBatch];
    const VertexId *x_[kBatch];
    unsigned ends_[kBatch];
  };

  // Room for `extra` more cells now (a limit trips past max_cells), and for
  // `ahead` (at least extra) if the arrays have to grow anyway.
  void reserve(std::size_t extra, std::size_t ahead) {
    const std::size_t need = m_.num_cells() + extra;
    if (need > limits_.max_cells) {
      if (logging_)
        throw LimitReached{};
      throw CheckError("cell ids would overflow 32 bits");
    }
    const std::size_t want =
        std::max(need, std::min(m_.num_cells() + std::max(extra, ahead), limits_.max_cells));
    if (m_.cells.capacity() >= want * N)
      return;
    // Growing copies the cell arrays into fresh pages while the old copy is
    // alive, so it is done early: an iteration first asks for room for 3
    // new cells per selected one (closure made 2.0 to 2.3 in the
    // benchmarks), and the arrays at least double. Growing only for each
    // pass's own bisections copied the arrays in the middle or at the end of
    // an iteration, at their largest (4D, 25 iterations to 5,233,296
    // pentatopes: peak 72 -> 62 bytes per pentatope). Growing 8x at a time
    // (address space only until written) copied less often but left the
    // peak at 65-70 bytes per pentatope and took address space that a
    // ulimit -v needed later.
    const std::size_t cap =
        std::min(std::max(want, 2 * m_.num_cells()), std::max(need, limits_.max_cells));
    m_.cells.reserve(cap * N);
    m_.stage.reserve(cap);
    m_.tag.reserve(cap);
    m_.generation.reserve(cap);
    // Cell data grows here too, not in finish(), when the iteration's
    // scratch (the midpoint table, the undo log) is largest.
    for (DataArray &a : m_.cell_data)
      a.values.reserve(cap * std::size_t(a.components));
  }

  VertexId midpoint(VertexId a, VertexId b) {
    std::uint64_t k = MidpointMap::key(a, b);
    VertexId next = VertexId(m_.num_vertices());
    VertexId z = mids_.insert(k, next);
    if (z != next)
      return z;
    if (std::size_t(next) + 1 > limits_.max_vertices) {
      if (logging_)
        throw LimitReached{};
      throw CheckError("vertex ids would overflow 32 bits");
    }
    if (!(resolution({a, b}) >= 1)) {
      if (logging_)
        throw PrecisionReached{};
      throw CheckError("closure would bisect an edge below the precision limit");
    }
    const double *p = m_.point(a), *q = m_.point(b);
    double mid[Dim];
    for (int k2 = 0; k2 < Dim; ++k2)
      mid[k2] = 0.5 * (p[k2] + q[k2]);
    m_.coords.insert(m_.coords.end(), mid, mid + Dim);
    m_.parent_edge.push_back(a);
    m_.parent_edge.push_back(b);
    m_.level.push_back(level_);
    if (endpoint_.size() * 64 <= next)
      endpoint_.push_back(0);
    endpoint_[a >> 6] |= std::uint64_t(1) << (a & 63);
    endpoint_[b >> 6] |= std::uint64_t(1) << (b & 63);
    return next;
  }

  // Reads what bisecting cell c reads at random: its edge's slot in the
  // midpoint table, the filter's word and the edge's end points (the value
  // means nothing). The serial loop reads them for kBisectBatch cells, then
  // bisects the cells: the reads of a batch wait for memory together. Asking
  // for them 8 cells ahead with prefetch instructions, as before,
  // saved nothing on this project's machine (AMD EPYC under a hypervisor: the
  // table's probe in midpoint() stalled as long with them as without, 8 or
  // 24 cells ahead); the batch took the refinement kernel from ~13,300 to
  // ~8,200 profile samples (3D benchmark, 13 iterations, one thread).
  static constexpr std::size_t kBisectBatch = 32;
  std::uint64_t touch_bisection(CellId c) const {
    const auto [a, b] = refinement_edge(c);
    return mids_.touch_key(MidpointMap::key(a, b)) ^ std::bit_cast<std::uint64_t>(m_.point(a)[0]) ^
           std::bit_cast<std::uint64_t>(m_.point(b)[0]);
  }

  // Bisects cell c by its refinement edge: child 1 in place, child 2 appended.
  void bisect(CellId c) {
    const VertexId *x = m_.cell(c);
    const Stage s = m_.stage[c];
    const int t = m_.tag[c];
    const std::uint16_t g = m_.generation[c];
    if (g == std::numeric_limits<std::uint16_t>::max())
      throw CheckError("a cell would pass 65535 generations of bisection");
    // The undo log keeps what an input cell was before its first bisection
    // in this call: cells appended by the call are dropped by undo() anyway,
    // and later bisections of the same cell change nothing undo() restores.
    if (logging_ && c < nc0_ && !(logged_[c >> 6] >> (c & 63) & 1)) {
      logged_[c >> 6] |= std::uint64_t(1) << (c & 63);
      UndoEntry u{c, {}, s, std::uint8_t(t), g};
      std::copy(x, x + N, u.x);
      log_.push_back(u);
    }
    if (Dim == 2 && s != Stage::Maubach)
      throw CheckError("Stage 1 cell in a 2D mesh");
    const EdgePick e = refinement_pick(c);
    const VertexId a = x[e.first], b = x[e.second];
    const VertexId z = midpoint(a, b);
    if (splitter_)
      splitter_->split(x, N, a, b, z);
    VertexId c2[N];
    const Child child = place_children(c, e, z, c2);
    m_.cells.insert(m_.cells.end(), c2, c2 + N);
    m_.stage.push_back(child.stage);
    m_.tag.push_back(child.tag);
    m_.generation.push_back(child.generation);
    origin_.push_back(c < nc0_ ? c : origin_[c - nc0_]);
  }

  // Whether a pass of `count` bisections runs on all threads (bisect_all):
  // not when the undo log, which is serial, is kept, nor for a small pass
  // (the threads cost more than they save).
  bool parallel_round(std::size_t count) const {
    if (logging_)
      return false;
    const int mode = testing::parallel_bisection();
    if (mode != 0)
      return mode > 0;
    return threads() > 1 && count >= kParallelPass;
  }
  static constexpr std::size_t kParallelPass = std::size_t(1) << 13;
  // walk_around() runs on all threads from this many new vertices (each
  // one's walk reads about a hundred cells).
  static constexpr std::size_t kParallelWalk = 256;
  // Around is built for a 3D input of this many cells or more; otherwise
  // every pass scans. Building costs ~33 ns an input tet on one thread; the
  // passes that walk instead of scanning saved 20-32 ns an input tet in
  // iterations from 0.25 to 3.7 M tets, 54 in one of 6.3 M, 34 in one of
  // 10.8 M and 171 in one of 18.3 M with 65 passes (Gmsh's 49,090-tet ball,
  // 12 and 14 iterations around the hemisphere, one thread, each pass timed
  // both ways; README). In 2D and 4D it never paid: the iterations saved
  // 10-16 ns an input triangle (a scan reads 12 bytes a cell) and 3-13 ns
  // an input pentatope (4D iterations have 4 to 8 passes, against 14 to 65
  // in 3D).
  static constexpr std::size_t kAroundFrom = std::size_t(1) << 22;
  static constexpr std::size_t kWalkCost = 8;

  // Bisects every cell of `work` (distinct cells) as bisect() would one after
  // the other, on all threads, with the same result to the bit: the
  // midpoint of an edge new in this pass gets the id the serial loop would
  // give it, the next free id in the order of the first cell that bisects
  // it, and the second child of work[i] goes to slot num_cells() + i.
  // 1. Each cell finds its edge and claims the edge's slot in the midpoint
  //    table; for a slot without a value, the smallest claiming index wins.
  // 2. Blocks count their winners; prefix sums give each winner its id.
  // 3. The tagged entities split, in work order on one thread, at the edges
  //    step 1 found may split one (most do not); then each cell writes its
  //    children, each winner its vertex.
  // Errors are found first, in the order the serial loop would meet them,
  // and nothing is changed but the table when one is thrown.
  void bisect_all(const std::vector<CellId> &work) {
    const std::size_t w = work.size(), nc = m_.num_cells(), nv = m_.num_vertices();
    constexpr std::size_t kBlock = std::size_t(1) << 11;
    // The passes after the claims read each cell's slot of the midpoint
    // table again, at random: asked for this many cells ahead.
    constexpr std::size_t kSlotAhead = 16;
    const std::size_t blocks = (w + kBlock - 1) / kBlock;
    const int workers = int(std::clamp<std::size_t>(blocks, 1, std::size_t(threads())));
    // Per cell of the pass, each entry written before it is read, and not
    // zeroed first: vectors zeroed their fresh pages on one thread before
    // the claims (21 bytes per cell; Gmsh's 3D ball, 14 iterations, two
    // threads: the kernel took 3.11-4.45 s, median 3.68, against 2.73-4.03,
    // median 3.13, in six runs each alternated). Kept from pass to pass,
    // they saved no more and raised the peak by 60 MB.
    const auto slot = std::make_unique_for_overwrite<std::uint32_t[]>(w);
    const auto pick = std::make_unique_for_overwrite<EdgePick[]>(w);
    const auto ends = std::make_unique_for_overwrite<VertexId[]>(2 * w);
    const auto flags = std::make_unique_for_overwrite<std::uint8_t[]>(w);
    std::vector<std::size_t> winners(blocks + 1, 0);
    // Per block: the first index with a defect, and which (kGenerations,
    // kIds, kPrecision, kStage in the serial loop's order at one cell).
    enum Defect : std::uint8_t { kNone, kGenerations, kIds, kPrecision, kStage };
    std::vector<std::pair<std::size_t, Defect>> defect(blocks, {w, kNone});
    auto note = [&](std::size_t b, std::size_t i, Defect d) {
      if (i < defect[b].first)
        defect[b] = {i, d};
    };
    // Per cell: kWon (its edge's midpoint is new and it is the first in
    // work order to bisect that edge), kSplits (its edge may split an
    // entity, EntitySplitter::may_split) and kMayWin (its bid was the
    // smallest when it bid: only these can have won).
    constexpr std::uint8_t kWon = 1, kSplits = 2, kMayWin = 4;
    mids_.begin_round(w);
    for (;;) {
#pragma omp parallel num_threads(workers)
      {
        std::size_t credits = 0; // MidpointMap::claim
#pragma omp for schedule(dynamic, 1)
        for (std::size_t b = 0; b < blocks; ++b) {
          const std::size_t end = std::min(w, (b + 1) * kBlock);
          // The edges first, then the claims, each asking for a slot of
          // the table kSlotAhead claims ahead.
          for (std::size_t i = b * kBlock; i < end; ++i) {
            const CellId c = work[i];
            pick[i] = refinement_pick(c);
            ends[2 * i] = m_.cell(c)[pick[i].first];
            ends[2 * i + 1] = m_.cell(c)[pick[i].second];
          }
          for (std::size_t i = b * kBlock; i < end; ++i) {
            const CellId c = work[i];
            if (i + kSlotAhead < end)
              mids_.prefetch_key(
                  MidpointMap::key(ends[2 * (i + kSlotAhead)], ends[2 * (i + kSlotAhead) + 1]));
            if (m_.generation[c] == std::numeric_limits<std::uint16_t>::max())
              note(b, i, kGenerations);
            if constexpr (Dim == 2)
              if (m_.stage[c] != Stage::Maubach)
                note(b, i, kStage);
            const VertexId a = ends[2 * i], z = ends[2 * i + 1];
            const std::uint32_t s = mids_.claim(MidpointMap::key(a, z), credits);
            if (s == MidpointMap::kNoSlot)
              continue; // the round overflowed: claimed again below
            slot[i] = s;
            const bool may_win = mids_.fresh(s) && mids_.bid(s, std::uint32_t(i));
            flags[i] = std::uint8_t((splitter_ && splitter_->may_split(a, z) ? kSplits : 0) |
                                    (may_win ? kMayWin : 0));
          }
        }
      }
      if (!mids_.overflowed())
        break;
      mids_.retry_round(w);
    }
    // 2. The winners (a bit in flags: settle() below forgets the bids) and
    // their ids, which depend on the blocks' order only. Only a cell whose
    // bid was the smallest when it bid reads its slot again, at random: a
    // few more than the winners (Gmsh's 3D ball, 14 iterations, two
    // threads: 5.65 M of 30.9 M cells for 5.56 M winners; every cell read
    // its slot here before, and the kernel took 3.22-3.86 s against
    // 3.14-3.31 now, three runs each alternated).
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (std::size_t b = 0; b < blocks; ++b)
      for (std::size_t i = b * kBlock; i < std::min(w, (b + 1) * kBlock); ++i) {
        if (i + kSlotAhead < w && flags[i + kSlotAhead] & kMayWin)
          mids_.prefetch_slot(slot[i + kSlotAhead]);
        const bool won = flags[i] & kMayWin && mids_.first_bidder(slot[i]) == std::uint32_t(i);
        flags[i] |= won ? kWon : 0;
        winners[b + 1] += won;
      }
    for (std::size_t b = 0; b < blocks; ++b)
      winners[b + 1] += winners[b];
    const std::size_t made = winners[blocks];
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (std::size_t b = 0; b < blocks; ++b) {
      std::size_t next = nv + winners[b];
      for (std::size_t i = b * kBlock; i < std::min(w, (b + 1) * kBlock); ++i)
        if (flags[i] & kWon) {
          if (next + 1 > limits_.max_vertices)
            note(b, i, kIds);
          else if (!(resolution({ends[2 * i], ends[2 * i + 1]}) >= 1))
            note(b, i, kPrecision);
          mids_.settle(slot[i], VertexId(next++));
        }
    }
    mids_.end_round(made);
    for (const auto &[i, d] : defect) // blocks in order: the first in work order
      switch (d) {
      case kNone:
        continue;
      case kGenerations:
        throw CheckError("a cell would pass 65535 generations of bisection");
      case kIds:
        throw CheckError("vertex ids would overflow 32 bits");
      case kPrecision:
        throw CheckError("closure would bisect an edge below the precision limit");
      case kStage:
        throw CheckError("Stage 1 cell in a 2D mesh");
      }
    // 3. Room (within the capacity reserve() made for the cells), then the
    // children and the new vertices. The arrays grow side by side, a group
    // per thread: on one thread, their first writes to fresh pages were
    // 0.95-1.01 s of this kernel's 3.6-3.7, in three groups 0.72-0.92
    // (Gmsh's 3D ball, 14 iterations, two threads, three runs each
    // alternated). An exception (the vertex arrays may reallocate) is
    // thrown after the others have grown.
    std::exception_ptr failed[3];
#pragma omp parallel sections num_threads(std::min(workers, 3))
    {
#pragma omp section
      try {
        m_.cells.resize((nc + w) * N);
      } catch (...) {
        failed[0] = std::current_exception();
      }
#pragma omp section
      try {
        m_.stage.resize(nc + w);
        m_.tag.resize(nc + w);
        m_.generation.resize(nc + w);
        origin_.resize(nc + w - nc0_);
      } catch (...) {
        failed[1] = std::current_exception();
      }
#pragma omp section
      try {
        m_.coords.resize((nv + made) * Dim);
        m_.parent_edge.resize(2 * (nv + made));
        m_.level.resize(nv + made, level_);
        endpoint_.resize((nv + made + 63) / 64, 0);
      } catch (...) {
        failed[2] = std::current_exception();
      }
    }
    for (const std::exception_ptr &e : failed)
      if (e)
        std::rethrow_exception(e);
    if (splitter_)
      for (std::size_t i = 0; i < w; ++i)
        if (flags[i] & kSplits)
          splitter_->split(m_.cell(work[i]), N, ends[2 * i], ends[2 * i + 1], mids_.value(slot[i]));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (std::size_t b = 0; b < blocks; ++b)
      for (std::size_t i = b * kBlock; i < std::min(w, (b + 1) * kBlock); ++i) {
        if (i + kSlotAhead < w)
          mids_.prefetch_slot(slot[i + kSlotAhead]);
        const VertexId z = mids_.value(slot[i]);
        if (flags[i] & kWon) {
          const VertexId a = ends[2 * i], e = ends[2 * i + 1];
          const double *p = m_.point(a), *q = m_.point(e);
          double *mid = m_.coords.data() + std::size_t(z) * Dim;
          for (int k = 0; k < Dim; ++k)
            mid[k] = 0.5 * (p[k] + q[k]);
          m_.parent_edge[2 * std::size_t(z)] = a;
          m_.parent_edge[2 * std::size_t(z) + 1] = e;
          std::atomic_ref<std::uint64_t>(endpoint_[a >> 6])
              .fetch_or(std::uint64_t(1) << (a & 63), std::memory_order_relaxed);
          std::atomic_ref<std::uint64_t>(endpoint_[e >> 6])
              .fetch_or(std::uint64_t(1) << (e & 63), std::memory_order_relaxed);
        }
        const std::size_t at = nc + i;
        const Child child = place_children(work[i], pick[i], z, m_.cells.data() + at * N);
        m_.stage[at] = child.stage;
        m_.tag[at] = child.tag;
        m_.generation[at] = child.generation;
        origin_[at - nc0_] = work[i] < nc0_ ? work[i] : origin_[work[i] - nc0_];
      }
  }

  // The children of cell c by its refinement edge e (refinement_pick),
  // whose midpoint is z: child 1 replaces c in its slot, child 2 goes to c2,
  // and both get the returned stage, tag and generation (which the caller
  // gives child 2). Reads only c and the edge order, so cells may be
  // bisected from several threads at once.
  struct Child {
    Stage stage;
    std::uint8_t tag;
    std::uint16_t generation;
  };
  Child place_children(CellId c, EdgePick e, VertexId z, VertexId *c2) {
    VertexId x[N], c1[N];
    std::copy(m_.cell(c), m_.cell(c) + N, x);
    const int t = m_.tag[c];
    Stage stage = Stage::Maubach;
    int tag;
    if (m_.stage[c] == Stage::Maubach) {
      maubach_children<Dim>(x, t, z, c1, c2);
      tag = maubach_child_tag(t, Dim);
    } else {
      opposite_children(order_, x, Dim, t, e, z, c1, c2, stage, tag);
    }
    const Child child{stage, std::uint8_t(tag), std::uint16_t(m_.generation[c] + 1)};
    std::copy(c1, c1 + N, m_.cell(c));
    m_.stage[c] = child.stage;
    m_.tag[c] = child.tag;
    m_.generation[c] = child.generation;
    return child;
  }

  void undo() {
    for (auto it = log_.rbegin(); it != log_.rend(); ++it) {
      std::copy(it->x, it->x + N, m_.cell(it->c));
      m_.stage[it->c] = it->s;
      m_.tag[it->c] = it->t;
      m_.generation[it->c] = it->g;
    }
    m_.generation.resize(nc0_);
    m_.parent_edge.resize(2 * nv0_);
    m_.level.resize(nv0_);
    m_.cells.resize(nc0_ * N);
    m_.stage.resize(nc0_);
    m_.tag.resize(nc0_);
    m_.coords.resize(nv0_ * Dim);
    m_.cells.shrink_to_fit();
    if (splitter_)
      m_.entities = std::move(entities0_);
  }

  // Children inherit cell data; point data is interpolated at midpoints,
  // except labels: an integer array's value where both ends share it, else
  // label_sentinel; is_label_array's arrays (colour, slice) always kNoLabel.
  void finish() {
    const int workers = threads();
    for (DataArray &a : m_.cell_data) {
      const std::size_t k = a.components;
      a.values.resize(m_.num_cells() * k);
      // origin_ names input cells only, which keep their values
#pragma omp parallel for num_threads(workers) schedule(static) if (origin_.size() > (1u << 16))
      for (std::size_t i = 0; i < origin_.size(); ++i)
        for (std::size_t j = 0; j < k; ++j)
          a.values[(nc0_ + i) * k + j] = a.values[std::size_t(origin_[i]) * k + j];
    }
    const VertexId *parents = m_.parent_edge.data() + 2 * nv0_;
    const std::size_t made = m_.num_vertices() - nv0_;
    for (DataArray &a : m_.point_data) {
      const std::size_t k = a.components;
      if (is_label_array(a.name)) {
        a.values.resize(m_.num_vertices() * k, kNoLabel);
        continue;
      }
      if (is_integer_type(a.type)) {
        // Integer labels: the value both ends share, else the sentinel.
        const double none = label_sentinel(a.type);
        a.values.resize(m_.num_vertices() * k);
        for (std::size_t i = 0; i < made; ++i)
          for (std::size_t j = 0; j < k; ++j) {
            const double p = a.values[parents[2 * i] * k + j],
                         q = a.values[parents[2 * i + 1] * k + j];
            a.values[(nv0_ + i) * k + j] = p == q ? p : none;
          }
        continue;
      }
      a.values.resize(m_.num_vertices() * k);
      for (std::size_t i = 0; i < made; ++i)
        for (std::size_t j = 0; j < k; ++j)
          a.values[(nv0_ + i) * k + j] =
              0.5 * (a.values[parents[2 * i] * k + j] + a.values[parents[2 * i + 1] * k + j]);
    }
  }

  struct UndoEntry {
    CellId c;
    VertexId x[N];
    Stage s;
    std::uint8_t t;
    std::uint16_t g;
  };

  Mesh &m_;
  EdgeOrder order_;
  RefineLimits limits_;
  std::size_t nc0_, nv0_;
  std::uint16_t level_ = 1; // of the vertices this call makes (mesh.hpp)
  bool logging_ = false;
  MidpointMap mids_;
  std::vector<CellId> origin_; // per appended cell: the input cell it descends from
  Around<N> around_;           // built for a 3D input of kAroundFrom cells or more
  // Per vertex, a bit: set for an end of an edge bisected so far (bits, not
  // bytes: 0.9 MB for 7 M vertices, read at random by the closure's tests;
  // no time saved was measured).
  std::vector<std::uint64_t> endpoint_;
  std::vector<UndoEntry> log_;
  std::vector<std::uint64_t> logged_;        // per input cell, when logging: 1 once in log_
  std::unique_ptr<EntitySplitter> splitter_; // null for a mesh without entities
  std::vector<Entities> entities0_;          // the entities before, when logging
};

template <int Dim>
RefineResult refine_dim(Mesh &mesh, const std::vector<CellId> &selected,
                        const std::vector<std::array<VertexId, 2>> &split,
                        const RefineLimits &limits) {
  Refiner<Dim> r(mesh, limits);
  return r.run(selected, split);
}

} // namespace

RefineResult refine(Mesh &mesh, const std::vector<CellId> &selected, const RefineLimits &limits) {
  return refine(mesh, selected, {}, limits);
}

RefineResult refine(Mesh &mesh, const std::vector<CellId> &selected,
                    const std::vector<std::array<VertexId, 2>> &split, const RefineLimits &limits) {
  if (!mesh.marked())
    throw CheckError("refine: the mesh is not marked");
  mesh.numbering = {}; // messages from here on name bisect's own ids
  return dispatch(mesh.dim, [&]<int D>() { return refine_dim<D>(mesh, selected, split, limits); });
}

RefineResult refine_uniform(Mesh &mesh) {
  std::vector<CellId> all(mesh.num_cells());
  for (std::size_t c = 0; c < all.size(); ++c)
    all[c] = CellId(c);
  return refine(mesh, all);
}

} // namespace bisect

namespace bisect::testing {
namespace {
std::atomic<int> g_parallel_bisection{0};
std::atomic<int> g_midpoint_room{0};
std::atomic<std::size_t> g_midpoint_retries{0};
std::atomic<bool> g_vector_scan{true}; // wanted; on where the processor has AVX2
std::atomic<int> g_walk_around{0};
std::atomic<std::size_t> g_walks{0};
bool has_avx2() {
#ifdef BISECT_SCAN_AVX2
  static const bool yes = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return yes;
#else
  return false;
#endif
}
} // namespace
void set_parallel_bisection(int mode) {
  g_parallel_bisection = mode;
}
int parallel_bisection() {
  return g_parallel_bisection;
}
void set_midpoint_room(int k) {
  g_midpoint_room = k;
  g_midpoint_retries = 0;
}
int midpoint_room() {
  return g_midpoint_room;
}
void count_midpoint_retry() {
  ++g_midpoint_retries;
}
std::size_t midpoint_retries() {
  return g_midpoint_retries;
}
void set_walk_around(int mode) {
  g_walk_around = mode;
}
int walk_around() {
  return g_walk_around;
}
void count_walk() {
  g_walks.fetch_add(1, std::memory_order_relaxed);
}
std::size_t walks() {
  return g_walks;
}

bool set_vector_scan(bool on) {
  g_vector_scan = on;
  return vector_scan();
}
bool vector_scan() {
  return g_vector_scan.load(std::memory_order_relaxed) && has_avx2();
}
} // namespace bisect::testing
