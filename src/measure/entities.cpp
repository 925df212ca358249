// Whether tagged entities are faces of the mesh (check.hpp).
#include "bisect/check.hpp"
#include "core/faces.hpp"

#include <unordered_map>
#include <vector>

namespace bisect {

std::size_t first_entity_not_a_face(const Mesh &mesh, const Entities &block) {
  constexpr std::size_t kAll = std::size_t(-1);
  const std::size_t n = block.size(), nv = mesh.num_vertices();
  const int count = block.dim + 1;
  if (n == 0)
    return kAll;
  if (block.dim < 0 || block.dim >= mesh.dim)
    return 0;
  // Entity keys -> found (duplicates share one entry); the entities are
  // usually far fewer than the cells' faces, so they are what is hashed.
  std::unordered_map<FaceKey, bool, FaceKeyHash> found;
  found.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const VertexId *v = block.entity(i);
    for (int k = 0; k < count; ++k)
      if (v[k] >= nv)
        return i;
    found.emplace(face_key(v, count), false);
  }
  std::size_t missing = found.size();
  const int cell_vertices = mesh.cell_size();
  // A face that is an entity has all its vertices on entities: cells with
  // fewer such vertices than an entity has are skipped without a lookup
  // (the entities are usually boundary facets, the cells mostly interior).
  std::vector<char> on_entity(nv, 0);
  for (VertexId v : block.vertices)
    on_entity[v] = 1;
  for (std::size_t c = 0; c < mesh.num_cells() && missing > 0; ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    int marked = 0;
    for (int i = 0; i < cell_vertices; ++i)
      marked += x[i] < nv && on_entity[x[i]]; // (ids are checked later)
    if (marked < count)
      continue;
    for_each_face(x, cell_vertices, block.dim, [&](const VertexId *face, int k) {
      for (int i = 0; i < k; ++i)
        if (!on_entity[face[i]])
          return;
      const auto it = found.find(face_key(face, k));
      if (it != found.end() && !it->second) {
        it->second = true;
        --missing;
      }
    });
  }
  if (missing == 0)
    return kAll;
  for (std::size_t i = 0; i < n; ++i)
    if (!found.at(face_key(block.entity(i), count)))
      return i;
  return kAll;
}

} // namespace bisect
