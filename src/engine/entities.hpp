// Tagged lower-dimensional entities (mesh.hpp, Entities) follow the cells:
// refine.cpp splits them as it bisects, coarsen.cpp merges them back.
#pragma once

#include "bisect/mesh.hpp"
#include "core/faces.hpp"

#include <unordered_map>
#include <vector>

namespace bisect {

// Splits the entities of a mesh that are faces of the cells bisected. Built
// once per refine() call (a hash of the entities' sorted ids); refine.cpp
// makes one only for a mesh with entities, so a mesh without any pays nothing.
class EntitySplitter {
public:
  explicit EntitySplitter(Mesh &mesh);
  // The cell x (n vertex ids) is being bisected at its edge (a, b), whose
  // midpoint is m: every entity that is a face of x holding a and b is
  // replaced by its halves, with a -> m and with b -> m, both keeping its data
  // (the first half keeps its slot, the second is appended to its block).
  // A face found here is gone when the next cell holding it is bisected at
  // the same edge, and that cell finds its halves, which it does not split
  // again: both halves hold m, not both a and b.
  void split(const VertexId *x, int n, VertexId a, VertexId b, VertexId m);
  // False when split() at the edge (a, b) does nothing: an end is on no
  // entity (most edges). Safe from several threads between split() calls.
  bool may_split(VertexId a, VertexId b) const { return on_entity(a) && on_entity(b); }

private:
  struct Ref {
    std::uint32_t block;
    std::uint32_t index;
  };
  void add(const FaceKey &key, Ref ref) { index_.emplace(key, ref); }

  bool on_entity(VertexId v) const { return v < on_entity_.size() && on_entity_[v]; }

  Mesh &m_;
  std::unordered_multimap<FaceKey, Ref, FaceKeyHash> index_;
  // Per vertex: 1 when it is a vertex of some entity that can split. Most
  // bisected edges have an end off every entity; this test spares them the
  // hash lookups.
  std::vector<char> on_entity_;
  unsigned dims_ = 0; // bit d: some block of dimension d >= 1 (points never split)
  std::vector<Ref> hits_;
};

// Coarsening: the vertices with removed[v] set go (each the midpoint of its
// parent edge (a, b) in mesh.parent_edge). The two halves {R, a, m} and
// {R, m, b} of an entity become {R, a, b} again (data of the first half,
// which is their common value when they agree); a half without its sibling
// still becomes {R, a, b}; an entity holding m but neither a nor b (a point
// at m, a face made inside a bisected cell) has no coarse counterpart and is
// dropped. Then the vertex ids are renumbered as coarsen compacts them (the
// kept vertices in order). Call before the mesh's vertices are compacted.
void merge_entities(Mesh &mesh, const std::vector<char> &removed);

} // namespace bisect
