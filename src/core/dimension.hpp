// Run-time dimension to compile-time kernel: the one switch (STYLE.md §3).
#pragma once

#include <stdexcept>
#include <string>

namespace bisect {

// Calls f.template operator()<Dim>() for dim in 2, 3, 4.
template <class F> decltype(auto) dispatch(int dim, F &&f) {
  switch (dim) {
  case 2:
    return f.template operator()<2>();
  case 3:
    return f.template operator()<3>();
  case 4:
    return f.template operator()<4>();
  }
  throw std::invalid_argument("unsupported dimension " + std::to_string(dim) +
                              " (expected 2, 3 or 4)");
}

} // namespace bisect
