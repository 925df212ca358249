// How many threads bisect's parallel loops use.
//
// Every result is the same for every thread count: the parallel loops split
// their work into pieces fixed by the data alone (never by the number of
// threads) and combine the pieces' results in a fixed order, so a mesh, a
// check's verdict and its message, and a sum of volumes come out bit for bit
// the same with 1 thread as with 32.
#pragma once

namespace bisect {

// Sets the number of threads; 0 (the default) means one per core.
void set_threads(int n);

// The number of threads the next parallel loop will use (at least 1).
int threads();

} // namespace bisect
