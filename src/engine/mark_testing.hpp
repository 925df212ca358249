// Test hooks of the marking module (not part of the installed API).
#pragma once

#include "bisect/mesh.hpp"

#include <cstdint>
#include <vector>

namespace bisect::testing {

// Whether check_state_consistency answers Maubach pairs from its table of
// renamed pairs (MaubachPairs in mark.cpp; the default) or walks every pair.
// Both must give the same verdict, which a test checks pair by pair.
void set_state_pair_table(bool on);

// For each pair k of Maubach cells sharing a facet (cells 2k and 2k + 1 of
// `cells`, dim + 1 ids each, with tags[2k] and tags[2k + 1]), whether the
// two bisect it alike: from one table shared by all pairs, or by walking
// each pair over its own ids.
std::vector<bool> state_pair_verdicts(int dim, const std::vector<VertexId> &cells,
                                      const std::vector<std::uint8_t> &tags, bool table);

} // namespace bisect::testing
