// Test hooks of the refinement kernel (not part of the installed API).
#pragma once

namespace bisect::testing {

// Which passes of refine-to-conformity bisect their cells on all threads
// (Refiner::bisect_all in refine.cpp): 0 (the default) the large ones when
// there is more than one thread, 1 every pass, even on one thread, -1 none.
// The result must be the same bit for bit, which a test checks.
void set_parallel_bisection(int mode);
int parallel_bisection();

} // namespace bisect::testing
