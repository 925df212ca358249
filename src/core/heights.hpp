// The order in which made vertices can be numbered so that parents come
// first (mesh.hpp: a vertex's parents have smaller ids): by level, then by
// height among the vertices of one level.
#pragma once

#include "bisect/mesh.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace bisect {

enum class HeightProblem { None, Cycle, ParentNewer };

// height[v] for v >= first: 0 when no parent q >= first has v's level, else
// one more than the highest such parent (parent: 2 per vertex, kNoVertex for
// none; parents below `first` are not looked at). Sets `problem` (and
// returns early) when a vertex is its own ancestor, or, with
// `check_levels`, when a parent q >= first has a higher level than v.
template <class Levels>
std::vector<int> parent_heights(const std::vector<VertexId> &parent, const Levels &level,
                                std::size_t first, bool check_levels, HeightProblem &problem) {
  const std::size_t n = parent.size() / 2;
  std::vector<int> height(n, -1); // -1 not yet, -2 waiting for its parents
  std::vector<VertexId> stack;
  problem = HeightProblem::None;
  for (std::size_t v0 = first; v0 < n; ++v0) {
    stack.assign(1, VertexId(v0));
    while (!stack.empty()) {
      const VertexId u = stack.back();
      if (height[u] >= 0) {
        stack.pop_back();
        continue;
      }
      int h = 0;
      bool ready = true;
      for (int k = 0; k < 2; ++k) {
        const VertexId q = parent[2 * std::size_t(u) + std::size_t(k)];
        if (q == kNoVertex || q < first)
          continue;
        if (check_levels && level[q] > level[u]) {
          problem = HeightProblem::ParentNewer;
          return height;
        }
        if (level[q] != level[u])
          continue;
        if (height[q] >= 0) {
          h = std::max(h, height[q] + 1);
        } else if (height[q] == -2 || q == u) {
          problem = HeightProblem::Cycle;
          return height;
        } else {
          stack.push_back(q);
          ready = false;
        }
      }
      if (ready) {
        height[u] = h;
        stack.pop_back();
      } else {
        height[u] = -2;
      }
    }
  }
  return height;
}

} // namespace bisect
