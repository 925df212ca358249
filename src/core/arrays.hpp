// Comparing data arrays (not installed).
#pragma once

#include "bisect/mesh.hpp"

#include <cstddef>
#include <vector>

namespace bisect {

// Whether `a` and `b` are the same arrays by name, components and type, in
// the same order (their values aside): pieces of one mesh must agree.
inline bool same_arrays(const std::vector<DataArray> &a, const std::vector<DataArray> &b) {
  if (a.size() != b.size())
    return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].name != b[i].name || a[i].components != b[i].components || a[i].type != b[i].type)
      return false;
  return true;
}

} // namespace bisect
