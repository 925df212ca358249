// Test hooks of the checks (not part of the installed API).
#pragma once

namespace bisect::testing {

// The final check (check_refined) matches most facets by hashing within the
// walk's coarse buckets and falls back to the sorted walk where it finds a
// defect. With `on`, it takes the sorted walk everywhere, so a test can
// compare the two: they must give the same verdict and message.
void use_sorted_final_walk(bool on);

} // namespace bisect::testing
