// Coarsening along the bisection tree (ALGORITHMS.md §10), the inverse of
// refine.cpp. A pass chooses the vertices of the newest level around them,
// then sweeps: find the chosen
// vertices whose whole star is marked and made of sibling pairs, pair the
// siblings by re-bisecting each reconstructed parent and comparing the
// children, replace every pair by its parent in place; until a sweep finds
// nothing. Then the removed cells and vertices are compacted out.
//
// Undo rules. Every child knows where its bisection put the new vertex z:
//   Maubach child, tag d':  z = y[d], d = d' + 1 if d' < n else 1 (§10);
//   Stage 1 child (Opposite, tag t' >= 1): z = y[0] (numbering.hpp);
//   Stage 1 child that entered Maubach, (alpha, gamma, beta, z, new...)_2:
//   z = y[3], the same index as for a Maubach child of tag 2.
// So a cell has one bisection vertex, and the stars of two removable
// vertices share no cell. The parent candidates of a child y, with e the end
// of z's parent edge y does not hold:
//   Maubach parent (§10): y with y[d] replaced by e when y[0] is an end, and
//   (e, y0 .. y(d-1), y(d+1) .. yn) when y[d-1] is one;
//   Stage 1 parent of an Opposite child (z, new.., S\p): (new.., S) with e
//   put back at any of the places in S\p (the child keeps S's order);
//   Stage 1 parent of a child that entered Maubach: (new.., S) with S any
//   order of {alpha, gamma, beta, e} (triangle_tuple forgets the order).
// A candidate is taken only when bisecting it (the kernels of refine.cpp:
// maubach_children, opposite_children) splits the edge {a, b} at z into
// exactly y and a cell of z's star, so every merge is exact; among several
// parents with the same two children (e.g. a tuple and its reflection) the
// first found is kept, and they are the same for all later refinement.
#include "bisect/coarsen.hpp"

#include "bisect/mark.hpp"
#include "core/dimension.hpp"
#include "core/numbering.hpp"
#include "engine/coarsen_pass.hpp"
#include "engine/entities.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_set>

namespace bisect {

namespace {

template <int Dim> class Coarsener {
  static constexpr int N = Dim + 1;

public:
  Coarsener(Mesh &mesh, std::vector<char> &marks, const CoarsenOptions &options)
      : m_(mesh), order_(edge_order(mesh)), marks_(marks) {
    auto named = [](const std::vector<std::string> &names, const std::string &name) {
      return std::find(names.begin(), names.end(), name) != names.end();
    };
    for (const DataArray &a : mesh.cell_data)
      rule_.push_back(named(options.sum_arrays, a.name)   ? Rule::Sum
                      : named(options.min_arrays, a.name) ? Rule::Min
                                                          : Rule::Common);
  }

  // A pass undoes the newest level of refinement around each vertex
  // (mesh.hpp, `level`): the vertices no vertex of whose star is newer are
  // removed in sweeps until a sweep finds nothing (a vertex waits for the
  // later bisections in its star, which are of its own level: midpoints are
  // shared only within one refine call); cells and vertices are compacted
  // once at the end.
  // `given`: the eligible vertices (coarsen_pass_among), instead of those
  // select_newest() finds; `removed`, when set, receives removed_.
  CoarsenPass run_pass(const std::vector<char> *given = nullptr,
                       std::vector<char> *removed = nullptr) {
    CoarsenPass report;
    const std::size_t nc = m_.num_cells(), nv = m_.num_vertices();
    dead_.assign(nc, 0);
    removed_.assign(nv, 0);
    removed_count_ = 0;
    if (given) {
      eligible_.assign(nv, 0);
      for (std::size_t v = 0; v < nv; ++v)
        eligible_[v] = (*given)[v] && m_.parent_edge[2 * v] != kNoVertex;
    } else {
      select_newest();
    }
    build_stars();
    std::vector<VertexId> work;
    for (std::size_t v = 0; v < nv; ++v)
      if (eligible_[v])
        work.push_back(VertexId(v));
    std::size_t merged = 0;
    for (;;) {
      sweep(work, merged);
      // Cycles of waiting vertices go together; what waited for them is
      // swept again.
      const std::size_t grouped = remove_groups();
      if (grouped == 0)
        break;
      merged += grouped;
      work.clear();
      for (std::size_t v = 0; v < nv; ++v)
        if (eligible_[v] && !removed_[v])
          work.push_back(VertexId(v));
    }
    report.removed_vertices = removed_count_;
    report.merged_pairs = merged;
    if (removed)
      *removed = removed_;
    if (merged) {
      compact_cells();
      remove_vertices();
    }
    report.cells = m_.num_cells();
    report.vertices = m_.num_vertices();
    return report;
  }

private:
  struct Merge {
    CellId keep, drop;
    VertexId x[N];
    Stage stage;
    std::uint8_t tag;
  };

  // Index in a child's tuple of the vertex its bisection made; -1 when the
  // state is that of no child.
  static int new_vertex_index(Stage s, int t) {
    if (s == Stage::Opposite)
      return t >= 1 ? 0 : -1;
    return t < Dim ? t + 1 : 1;
  }

  static bool is_edge(VertexId p, VertexId q, VertexId a, VertexId b) {
    return (p == a && q == b) || (p == b && q == a);
  }

  // Bisects the candidate parent (x, s, t) symbolically; false when its
  // refinement edge is not {a, b}.
  bool bisect_as(const VertexId *x, Stage s, int t, VertexId z, VertexId a, VertexId b,
                 VertexId *c1, VertexId *c2, Stage &cs, int &ct) const {
    if (s == Stage::Maubach) {
      if (!is_edge(x[0], x[t], a, b))
        return false;
      maubach_children<Dim>(x, t, z, c1, c2);
      cs = Stage::Maubach;
      ct = maubach_child_tag(t, Dim);
      return true;
    }
    if constexpr (Dim >= 3) {
      const EdgePick e = opposite_edge(order_, x, Dim, t);
      if (!is_edge(x[e.first], x[e.second], a, b))
        return false;
      opposite_children(order_, x, Dim, t, e, z, c1, c2, cs, ct);
      return true;
    }
    return false;
  }

  // Whether tuples p and q (both with state (s, t)) bisect alike: equal, or
  // (not exact) a Maubach tuple and its reflection (§1), or Stage 1 tuples
  // with the same new vertices and the same old sub-simplex in another order
  // (its consistent edge does not depend on the order, and the children differ
  // only by reflections).
  static bool same_cell(const VertexId *p, const VertexId *q, Stage s, int t, bool exact) {
    if (std::equal(p, p + N, q))
      return true;
    if (exact)
      return false;
    if (s == Stage::Maubach)
      return std::equal(p, p + t + 1, std::reverse_iterator<const VertexId *>(q + t + 1)) &&
             std::equal(p + t + 1, p + N, q + t + 1);
    if (!std::equal(p, p + t, q))
      return false;
    VertexId a[N], b[N];
    std::copy(p + t, p + N, a);
    std::copy(q + t, q + N, b);
    std::sort(a, a + N - t);
    std::sort(b, b + N - t);
    return std::equal(a, a + N - t, b);
  }

  // The cell of `star` (unpaired, other than y) that is c with state (s, t)
  // and generation g (see same_cell); -1 when there is none.
  std::size_t find_in_star(const CellId *star, std::size_t k, const std::vector<char> &paired,
                           std::size_t self, const VertexId *c, Stage s, int t, std::uint16_t g,
                           bool exact) const {
    for (std::size_t j = 0; j < k; ++j) {
      if (j == self || paired[j])
        continue;
      const CellId o = star[j];
      if (m_.stage[o] != s || m_.tag[o] != t || m_.generation[o] != g)
        continue;
      if (same_cell(c, m_.cell(o), s, t, exact))
        return j;
    }
    return std::size_t(-1);
  }

  // Tries candidate parent (x, s, t) for star[i]: when it bisects into
  // star[i] and another unpaired cell of the star, records the merge.
  bool try_parent(const VertexId *x, Stage s, int t, VertexId z, VertexId a, VertexId b,
                  const CellId *star, std::size_t k, std::size_t i, std::vector<char> &paired,
                  std::vector<Merge> &out) const {
    VertexId c1[N], c2[N];
    Stage cs;
    int ct;
    if (!bisect_as(x, s, t, z, a, b, c1, c2, cs, ct))
      return false;
    const CellId y = star[i];
    if (m_.stage[y] != cs || m_.tag[y] != ct)
      return false;
    const VertexId *yx = m_.cell(y);
    const VertexId *sibling;
    if (same_cell(c1, yx, cs, ct, exact_))
      sibling = c2;
    else if (same_cell(c2, yx, cs, ct, exact_))
      sibling = c1;
    else
      return false;
    const std::size_t j =
        find_in_star(star, k, paired, i, sibling, cs, ct, m_.generation[y], exact_);
    if (j == std::size_t(-1))
      return false;
    paired[i] = paired[j] = 1;
    Merge mg{std::min(y, star[j]), std::max(y, star[j]), {}, s, std::uint8_t(t)};
    std::copy(x, x + N, mg.x);
    out.push_back(mg);
    return true;
  }

  bool pair_maubach(VertexId z, VertexId a, VertexId b, const CellId *star, std::size_t k,
                    std::size_t i, std::vector<char> &paired, std::vector<Merge> &out) const {
    const CellId y = star[i];
    if (m_.stage[y] != Stage::Maubach)
      return false;
    const VertexId *yx = m_.cell(y);
    const int d = new_vertex_index(Stage::Maubach, m_.tag[y]);
    auto other = [&](VertexId v) { return v == a ? b : v == b ? a : kNoVertex; };
    VertexId x[N];
    if (const VertexId e = other(yx[0]); e != kNoVertex) {
      std::copy(yx, yx + N, x);
      x[d] = e;
      if (try_parent(x, Stage::Maubach, d, z, a, b, star, k, i, paired, out))
        return true;
    }
    if (const VertexId e = other(yx[d - 1]); e != kNoVertex) {
      x[0] = e;
      std::copy(yx, yx + d, x + 1);
      std::copy(yx + d + 1, yx + N, x + d + 1);
      if (try_parent(x, Stage::Maubach, d, z, a, b, star, k, i, paired, out))
        return true;
    }
    return false;
  }

  bool pair_stage1(VertexId z, VertexId a, VertexId b, const CellId *star, std::size_t k,
                   std::size_t i, std::vector<char> &paired, std::vector<Merge> &out) const {
    if constexpr (Dim < 3) {
      return false;
    } else {
      const CellId y = star[i];
      const VertexId *yx = m_.cell(y);
      const int ty = m_.tag[y];
      VertexId x[N];
      if (m_.stage[y] == Stage::Opposite) {
        // y = (z, new.., S\p) with ty new vertices; the parent has ty - 1.
        const int t = ty - 1, old = N - ty; // |S \ p|
        VertexId e = kNoVertex;
        for (int j = ty; j < N; ++j)
          if (yx[j] == a || yx[j] == b)
            e = yx[j] == a ? b : a;
        if (e == kNoVertex)
          return false;
        std::copy(yx + 1, yx + ty, x);
        for (int place = 0; place <= old; ++place) {
          VertexId *s = x + t;
          std::copy(yx + ty, yx + ty + place, s);
          s[place] = e;
          std::copy(yx + ty + place, yx + N, s + place + 1);
          if (try_parent(x, Stage::Opposite, t, z, a, b, star, k, i, paired, out))
            return true;
        }
        return false;
      }
      if (ty != 2)
        return false;
      // y = (alpha, gamma, beta, z, new..)_2; the parent (new.., S), S of 4.
      const int t = Dim - 3;
      VertexId s[4] = {yx[0], yx[1], yx[2], kNoVertex};
      for (int j = 0; j < 3; ++j)
        if (yx[j] == a || yx[j] == b)
          s[3] = yx[j] == a ? b : a;
      if (s[3] == kNoVertex)
        return false;
      std::copy(yx + 4, yx + N, x);
      std::sort(s, s + 4);
      do {
        std::copy(s, s + 4, x + t);
        if (try_parent(x, Stage::Opposite, t, z, a, b, star, k, i, paired, out))
          return true;
      } while (std::next_permutation(s, s + 4));
      return false;
    }
  }

  // A Maubach cell with tag n made by bisection is (h, z, ...) with h an end
  // of z's parent edge. An earlier merge may have stored its reflection (the
  // whole tuple reversed, §1: the same descendants, since the children of a
  // tag-1 cell do not tell it from its reflection), which puts z at n-1;
  // turn it back so that z is at 1 where the undo rule looks for it.
  void orient(VertexId *x) const {
    auto holds = [&](VertexId z, VertexId h) {
      return m_.parent_edge[2 * std::size_t(z)] == h || m_.parent_edge[2 * std::size_t(z) + 1] == h;
    };
    if (!holds(x[1], x[0]) && holds(x[Dim - 1], x[Dim]))
      std::reverse(x, x + N);
  }

  // Sweeps from `work` until one finds nothing; each sweep's next work is
  // the vertices of the parents it made (their stars changed).
  void sweep(std::vector<VertexId> work, std::size_t &merged) {
    std::vector<char> queued(m_.num_vertices(), 0);
    while (!work.empty()) {
      find_merges(work);
      merged += merges_.size();
      apply_merges();
      // Next sweep: the vertices of the parents (their stars changed).
      work.clear();
      for (const Merge &mg : merges_)
        for (const VertexId x : mg.x)
          if (eligible_[x] && !removed_[x] && !queued[x]) {
            queued[x] = 1;
            work.push_back(x);
          }
      for (const VertexId x : work)
        queued[x] = 0;
    }
  }

  // The cells around each eligible vertex at the start of the pass (CSR).
  // Later, a cell of a vertex's list may have died: its merge put the parent
  // in the sibling's slot (alias_), which holds the vertex unless it is the
  // removed one.
  void build_stars() {
    const std::size_t nv = m_.num_vertices(), nc = m_.num_cells();
    star_start_.assign(nv + 1, 0);
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = m_.cell(CellId(c));
      for (int i = 0; i < N; ++i)
        star_start_[x[i] + 1] += eligible_[x[i]];
    }
    for (std::size_t v = 0; v < nv; ++v)
      star_start_[v + 1] += star_start_[v];
    star_cells_.resize(star_start_[nv]);
    std::vector<std::uint32_t> fill(star_start_.begin(), star_start_.end() - 1);
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = m_.cell(CellId(c));
      for (int i = 0; i < N; ++i)
        if (eligible_[x[i]])
          star_cells_[fill[x[i]]++] = CellId(c);
    }
    alias_.assign(nc, kNoCell);
  }

  CellId live(CellId c) const {
    while (alias_[c] != kNoCell)
      c = alias_[c];
    return c;
  }

  // The cells around v now, when all of them are marked children of v's
  // bisection (an even number); else empty.
  bool children_star(VertexId v, std::vector<CellId> &star) {
    star.clear();
    for (std::uint32_t i = star_start_[v]; i < star_start_[v + 1]; ++i) {
      const CellId c = live(star_cells_[i]);
      VertexId *x = m_.cell(c);
      if (std::find(x, x + N, v) == x + N || std::find(star.begin(), star.end(), c) != star.end())
        continue;
      if (!marks_[c] || m_.generation[c] == 0)
        return false;
      if (m_.stage[c] == Stage::Maubach && m_.tag[c] == Dim)
        orient(x);
      const int k = new_vertex_index(m_.stage[c], m_.tag[c]);
      if (k < 0 || x[k] != v)
        return false;
      star.push_back(c);
    }
    return !star.empty() && star.size() % 2 == 0;
  }

  // Pairs star[i] (a child of z's bisection of {a, b}) with its sibling in
  // the star, recording the merge; false when there is none.
  bool pair_one(VertexId z, VertexId a, VertexId b, const std::vector<CellId> &star, std::size_t i,
                std::vector<char> &paired, std::vector<Merge> &found) {
    const std::size_t k = star.size();
    const CellId y = star[i];
    // Stage 1 parents come first for a tag-2 Maubach child young enough
    // to have entered Maubach from Stage 1 (generation <= n - 2).
    const bool stage1_first =
        Dim >= 3 && m_.stage[y] == Stage::Maubach && m_.tag[y] == 2 && m_.generation[y] <= Dim - 2;
    // The parent itself when it is found (children equal to the cells);
    // else one that bisects alike (same_cell), e.g. after a Stage 1
    // merge forgot the order of an old sub-simplex.
    for (int pass = 0; pass < 2; ++pass) {
      exact_ = pass == 0;
      const bool ok = stage1_first ? pair_stage1(z, a, b, star.data(), k, i, paired, found) ||
                                         pair_maubach(z, a, b, star.data(), k, i, paired, found)
                                   : pair_maubach(z, a, b, star.data(), k, i, paired, found) ||
                                         pair_stage1(z, a, b, star.data(), k, i, paired, found);
      if (ok)
        return true;
    }
    return false;
  }

  // The bisection vertex of live cell c, or kNoVertex when c cannot be
  // merged (unmarked, generation 0, no state of a child, an original vertex).
  VertexId bisection_vertex(CellId c) {
    if (!marks_[c] || m_.generation[c] == 0)
      return kNoVertex;
    VertexId *x = m_.cell(c);
    if (m_.stage[c] == Stage::Maubach && m_.tag[c] == Dim)
      orient(x);
    const int k = new_vertex_index(m_.stage[c], m_.tag[c]);
    if (k < 0 || m_.parent_edge[2 * std::size_t(x[k])] == kNoVertex)
      return kNoVertex;
    return x[k];
  }

  // The live cells around v (from its star list at the start of the pass).
  void live_star(VertexId v, std::vector<CellId> &star) const {
    star.clear();
    for (std::uint32_t i = star_start_[v]; i < star_start_[v + 1]; ++i) {
      const CellId c = live(star_cells_[i]);
      const VertexId *x = m_.cell(c);
      if (std::find(x, x + N, v) != x + N && std::find(star.begin(), star.end(), c) == star.end())
        star.push_back(c);
    }
  }

  // Vertices that wait for each other in a cycle (each one's star holds a
  // cell bisected at the next, a midpoint reused within one refine call) can
  // only go together. From each eligible vertex still there: the group of
  // the bisection vertices of its star, closed (all eligible, at most
  // kMaxGroup); then sibling pairs at any of them are merged, leaves first,
  // until none is left. When no cell holds a vertex of the group any more,
  // the group is gone; otherwise every merge of the try is undone. Returns
  // the number of merges kept.
  static constexpr std::size_t kMaxGroup = 64;
  struct Saved {
    Merge merge;
    VertexId x[N];
    Stage stage;
    std::uint8_t tag;
    std::uint16_t generation;
    char mark;
    std::vector<double> values; // the keep cell's data, array by array
  };

  std::size_t remove_groups() {
    std::size_t kept = 0;
    const std::size_t nv = m_.num_vertices();
    std::vector<char> tried(nv, 0);
    std::vector<VertexId> group;
    std::vector<CellId> star, children;
    std::vector<char> paired;
    std::vector<Merge> found;
    std::vector<Saved> saved;
    for (std::size_t v0 = 0; v0 < nv; ++v0) {
      if (!eligible_[v0] || removed_[v0] || tried[v0])
        continue;
      // The group: closed under "waits for".
      group.assign(1, VertexId(v0));
      tried[v0] = 1;
      bool ok = true;
      for (std::size_t g = 0; g < group.size() && ok; ++g) {
        live_star(group[g], star);
        for (const CellId c : star) {
          const VertexId z = bisection_vertex(c);
          if (z == kNoVertex || !eligible_[z] || removed_[z]) {
            ok = false;
            break;
          }
          if (std::find(group.begin(), group.end(), z) == group.end()) {
            if (group.size() == kMaxGroup) {
              ok = false;
              break;
            }
            group.push_back(z);
          }
        }
      }
      if (!ok || group.size() < 2)
        continue;
      // Merge sibling pairs at the group's vertices until none is left.
      saved.clear();
      for (bool progress = true; progress;) {
        progress = false;
        for (const VertexId z : group) {
          live_star(z, star);
          children.clear();
          for (const CellId c : star)
            if (bisection_vertex(c) == z)
              children.push_back(c);
          const VertexId a = m_.parent_edge[2 * std::size_t(z)],
                         b = m_.parent_edge[2 * std::size_t(z) + 1];
          paired.assign(children.size(), 0);
          found.clear();
          for (std::size_t i = 0; i < children.size(); ++i)
            if (!paired[i])
              pair_one(z, a, b, children, i, paired, found);
          for (const Merge &mg : found)
            saved.push_back(save(mg));
          merges_ = found;
          apply_merges();
          progress |= !found.empty();
        }
      }
      bool gone = true;
      for (const VertexId z : group) {
        live_star(z, star);
        gone &= star.empty();
      }
      if (gone) {
        for (const VertexId z : group)
          removed_[z] = 1;
        removed_count_ += group.size();
        kept += saved.size();
      } else {
        for (auto it = saved.rbegin(); it != saved.rend(); ++it)
          restore(*it);
      }
    }
    merges_.clear();
    return kept;
  }

  Saved save(const Merge &mg) const {
    Saved s{mg, {}, m_.stage[mg.keep], m_.tag[mg.keep], m_.generation[mg.keep], marks_[mg.keep],
            {}};
    std::copy(m_.cell(mg.keep), m_.cell(mg.keep) + N, s.x);
    for (const DataArray &a : m_.cell_data) {
      const std::size_t k = std::size_t(a.components);
      s.values.insert(s.values.end(), a.values.begin() + mg.keep * k,
                      a.values.begin() + (mg.keep + 1) * k);
    }
    return s;
  }

  void restore(const Saved &s) {
    const std::size_t w = s.merge.keep, d = s.merge.drop;
    std::copy(s.x, s.x + N, m_.cell(CellId(w)));
    m_.stage[w] = s.stage;
    m_.tag[w] = s.tag;
    m_.generation[w] = s.generation;
    marks_[w] = s.mark;
    std::size_t at = 0;
    for (DataArray &a : m_.cell_data) {
      const std::size_t k = std::size_t(a.components);
      std::copy(s.values.begin() + at, s.values.begin() + at + k, a.values.begin() + w * k);
      at += k;
    }
    dead_[d] = 0;
    alias_[d] = kNoCell;
  }

  // The merges of this sweep: for every vertex of `work` that is eligible,
  // still there, and whose star is all marked children of its bisection,
  // pairs of siblings.
  void find_merges(const std::vector<VertexId> &work) {
    merges_.clear();
    std::vector<CellId> star;
    std::vector<char> paired;
    std::vector<Merge> found;
    for (const VertexId v : work) {
      if (!eligible_[v] || removed_[v] || !children_star(v, star))
        continue;
      const std::size_t k = star.size();
      const VertexId z = v, a = m_.parent_edge[2 * std::size_t(v)],
                     b = m_.parent_edge[2 * std::size_t(v) + 1];
      paired.assign(k, 0);
      found.clear();
      bool ok = true;
      for (std::size_t i = 0; i < k && ok; ++i)
        ok = paired[i] || pair_one(z, a, b, star, i, paired, found);
      if (!ok)
        continue;
      merges_.insert(merges_.end(), found.begin(), found.end());
      removed_[v] = 1;
      ++removed_count_;
    }
  }

  // The level of vertex v (mesh.hpp): 0 original, else the stored level or 1.
  std::uint16_t level(std::size_t v) const {
    if (m_.level.size() == m_.num_vertices())
      return m_.level[v];
    return m_.parent_edge[2 * v] == kNoVertex ? 0 : 1;
  }

  // The made vertices no vertex of whose star is newer: where the newest
  // level around them is their own.
  void select_newest() {
    const std::size_t nv = m_.num_vertices(), nc = m_.num_cells();
    std::vector<std::uint16_t> around(nv, 0);
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = m_.cell(CellId(c));
      std::uint16_t top = 0;
      for (int i = 0; i < N; ++i)
        top = std::max(top, level(x[i]));
      for (int i = 0; i < N; ++i)
        around[x[i]] = std::max(around[x[i]], top);
    }
    eligible_.assign(nv, 0);
    for (std::size_t v = 0; v < nv; ++v)
      eligible_[v] = m_.parent_edge[2 * v] != kNoVertex && level(v) >= around[v];
  }

  // Each pair becomes its parent in the keep slot; the drop slot dies (it is
  // compacted out at the end of the pass).
  void apply_merges() {
    for (const Merge &mg : merges_) {
      const std::size_t w = mg.keep, d = mg.drop;
      std::copy(mg.x, mg.x + N, m_.cell(CellId(w)));
      m_.stage[w] = mg.stage;
      m_.tag[w] = mg.tag;
      m_.generation[w] = std::uint16_t(m_.generation[w] - 1);
      marks_[w] = 1;
      for (std::size_t i = 0; i < m_.cell_data.size(); ++i) {
        DataArray &a = m_.cell_data[i];
        const std::size_t k = std::size_t(a.components);
        for (std::size_t j = 0; j < k; ++j) {
          const double p = a.values[w * k + j], q = a.values[d * k + j];
          a.values[w * k + j] = rule_[i] == Rule::Sum   ? p + q
                                : rule_[i] == Rule::Min ? std::min(p, q)
                                : p == q                ? p
                                                        : 0.5 * (p + q);
        }
      }
      dead_[d] = 1;
      alias_[d] = CellId(w);
    }
  }

  // Removes the dead cells; survivors keep their relative order.
  void compact_cells() {
    const std::size_t nc = m_.num_cells();
    std::size_t w = 0;
    for (std::size_t c = 0; c < nc; ++c) {
      if (dead_[c])
        continue;
      if (w != c) {
        std::copy(m_.cell(CellId(c)), m_.cell(CellId(c)) + N, m_.cell(CellId(w)));
        m_.stage[w] = m_.stage[c];
        m_.tag[w] = m_.tag[c];
        m_.generation[w] = m_.generation[c];
        marks_[w] = marks_[c];
        for (DataArray &a : m_.cell_data) {
          const std::size_t k = std::size_t(a.components);
          std::copy(a.values.begin() + c * k, a.values.begin() + (c + 1) * k,
                    a.values.begin() + w * k);
        }
      }
      ++w;
    }
    m_.cells.resize(w * N);
    m_.stage.resize(w);
    m_.tag.resize(w);
    m_.generation.resize(w);
    marks_.resize(w);
    for (DataArray &a : m_.cell_data)
      a.values.resize(w * std::size_t(a.components));
  }

  void remove_vertices() {
    merge_entities(m_, removed_);
    const std::size_t nv = m_.num_vertices();
    std::vector<VertexId> id(nv, kNoVertex);
    std::size_t w = 0;
    for (std::size_t v = 0; v < nv; ++v) {
      if (removed_[v])
        continue;
      id[v] = VertexId(w);
      std::copy(m_.coords.begin() + v * Dim, m_.coords.begin() + (v + 1) * Dim,
                m_.coords.begin() + w * Dim);
      for (DataArray &a : m_.point_data) {
        const std::size_t k = std::size_t(a.components);
        std::copy(a.values.begin() + v * k, a.values.begin() + (v + 1) * k,
                  a.values.begin() + w * k);
      }
      VertexId p = m_.parent_edge[2 * v], q = m_.parent_edge[2 * v + 1];
      bool lost = false;
      if (p != kNoVertex) {
        p = id[p];
        q = id[q];
        // Cannot happen for a tree bisect made (a vertex's parents are in
        // its star until it goes); a vertex that lost one becomes original.
        if (p == kNoVertex || q == kNoVertex) {
          p = q = kNoVertex;
          lost = true;
        }
      }
      m_.parent_edge[2 * w] = p;
      m_.parent_edge[2 * w + 1] = q;
      // (A part of a distributed mesh may hold a made vertex without its
      // parents: it keeps its level.)
      if (m_.level.size() == nv)
        m_.level[w] = lost ? 0 : m_.level[v];
      ++w;
    }
    m_.coords.resize(w * Dim);
    m_.parent_edge.resize(2 * w);
    if (m_.level.size() == nv)
      m_.level.resize(w);
    for (DataArray &a : m_.point_data)
      a.values.resize(w * std::size_t(a.components));
    for (VertexId &x : m_.cells)
      x = id[x];
    if (!m_.edge_rank.empty()) {
      std::unordered_map<std::uint64_t, std::uint32_t> rank;
      for (const auto &[key, r] : m_.edge_rank) {
        const VertexId p = id[key >> 32], q = id[key & 0xffffffffu];
        if (p != kNoVertex && q != kNoVertex)
          rank.emplace(edge_key(p, q), r);
      }
      m_.edge_rank = std::move(rank);
    }
  }

  Mesh &m_;
  EdgeOrder order_;
  std::vector<char> &marks_;
  // How a parent's value comes from its children's (CoarsenOptions).
  enum class Rule : std::uint8_t { Common, Sum, Min };
  std::vector<Rule> rule_;                // per cell array
  std::vector<char> dead_;                // per cell, this pass: merged into its sibling's slot
  std::vector<char> eligible_;            // per vertex, this pass: may be removed
  std::vector<std::uint32_t> star_start_; // per vertex + 1: its cells in star_cells_
  std::vector<CellId> star_cells_;        // at the start of the pass (build_stars)
  std::vector<CellId> alias_;             // per cell: the slot it was merged into
  std::vector<Merge> merges_;
  std::vector<char> removed_; // per vertex, this pass
  std::size_t removed_count_ = 0;
  bool exact_ = true; // the matching try_parent uses (same_cell)
};

} // namespace

namespace {
// The arrays options name must be the mesh's: a misspelt name would
// silently leave its array under the default rule.
void check_array_names(const Mesh &mesh, const CoarsenOptions &options) {
  for (const std::vector<std::string> *names : {&options.sum_arrays, &options.min_arrays})
    for (const std::string &name : *names)
      if (std::none_of(mesh.cell_data.begin(), mesh.cell_data.end(),
                       [&](const DataArray &a) { return a.name == name; })) {
        std::string have;
        for (const DataArray &a : mesh.cell_data)
          have += (have.empty() ? "'" : ", '") + a.name + "'";
        throw UsageError("coarsen: no cell array '" + name + "' to " +
                         (names == &options.sum_arrays ? "sum" : "take the minimum of") +
                         " (the mesh has " + (have.empty() ? "none" : have) + ")");
      }
}
} // namespace

CoarsenPass coarsen_pass_among(Mesh &mesh, std::vector<char> &marks,
                               const std::vector<char> &eligible, const CoarsenOptions &options,
                               std::vector<char> &removed) {
  if (marks.size() != mesh.num_cells() || eligible.size() != mesh.num_vertices())
    throw std::logic_error("coarsen_pass_among: marks or eligibility not sized for the mesh");
  check_array_names(mesh, options);
  removed.assign(mesh.num_vertices(), 0);
  if (!mesh.marked() || !mesh.has_tree())
    return {};
  mesh.numbering = {};
  return dispatch(mesh.dim, [&]<int D>() {
    Coarsener<D> c(mesh, marks, options);
    return c.run_pass(&eligible, &removed);
  });
}

CoarsenResult coarsen(Mesh &mesh, const std::vector<char> &marked_cells,
                      const CoarsenOptions &options,
                      const std::function<void(const CoarsenPass &)> &on_pass) {
  if (marked_cells.size() != mesh.num_cells())
    throw UsageError("coarsen: " + std::to_string(marked_cells.size()) + " marks for " +
                     std::to_string(mesh.num_cells()) + " cells");
  check_array_names(mesh, options);
  CoarsenResult result;
  if (!mesh.marked() || !mesh.has_tree())
    return result;
  mesh.numbering = {}; // messages from here on name bisect's own ids
  std::vector<char> marks = marked_cells;
  for (int p = 1; options.passes <= 0 || p <= options.passes; ++p) {
    CoarsenPass pass = dispatch(mesh.dim, [&]<int D>() {
      Coarsener<D> c(mesh, marks, options);
      return c.run_pass();
    });
    pass.pass = p;
    if (on_pass)
      on_pass(pass);
    if (pass.removed_vertices == 0)
      break;
    result.passes = p;
    result.removed_vertices += pass.removed_vertices;
    result.merged_pairs += pass.merged_pairs;
  }
  return result;
}

} // namespace bisect
