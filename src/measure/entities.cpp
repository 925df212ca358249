// Whether tagged entities are faces of the mesh (check.hpp).
#include "bisect/check.hpp"
#include "core/faces.hpp"

#include <unordered_map>

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
  for (std::size_t c = 0; c < mesh.num_cells() && missing > 0; ++c)
    for_each_face(mesh.cell(CellId(c)), cell_vertices, block.dim, [&](const VertexId *face, int k) {
      const auto it = found.find(face_key(face, k));
      if (it != found.end() && !it->second) {
        it->second = true;
        --missing;
      }
    });
  if (missing == 0)
    return kAll;
  for (std::size_t i = 0; i < n; ++i)
    if (!found.at(face_key(block.entity(i), count)))
      return i;
  return kAll;
}

} // namespace bisect
