// Test hooks of the refinement kernel (not part of the installed API).
#pragma once

#include <cstddef>

namespace bisect::testing {

// Which passes of refine-to-conformity bisect their cells on all threads
// (Refiner::bisect_all in refine.cpp): 0 (the default) the large ones when
// there is more than one thread, 1 every pass, even on one thread, -1 none.
// The result must be the same bit for bit, which a test checks.
void set_parallel_bisection(int mode);
int parallel_bisection();

// The room a parallel pass makes in the midpoint table for the edges it
// bisects (MidpointMap::begin_round): 0 (the default) for half its cells,
// k > 0 for 1/k of them, so that passes overflow the table and claim their
// edges again (counted by midpoint_retries()). The result must not change.
void set_midpoint_room(int k);
std::size_t midpoint_retries();

// Whether the closure's scan for cells holding both ends of a bisected edge
// reads eight cells at a time with AVX2 (the default where the processor
// has it) or one at a time. The result must be the same bit for bit.
// Returns whether the vector scan is now on (never without AVX2).
bool set_vector_scan(bool on);

// How the closure finds the cells holding both ends of an edge a pass
// bisected (Refiner::run in refine.cpp): 0 (the default) by walking the
// cells around the edge's root (Around) in the passes where that costs
// less than a scan of every cell, for a 3D input of kAroundFrom cells
// or more; 1 by walking in every pass that makes midpoints, for any input;
// -1 always by the scan. The result must be the same bit for bit.
void set_walk_around(int mode);
std::size_t walks(); // passes that walked, so far

} // namespace bisect::testing
