// Test hooks of the .msh reader (not part of the installed API).
#pragma once

namespace bisect::testing {

// Whether the reader keeps the elements of a binary file as runs while their
// tags run on by one (ElementRun in msh.cpp), and a data section's row tags
// as a first tag and a count while they do (DataBlock; both the default),
// or one reference and one tag each. Both must read the same mesh and give
// the same messages, which a test checks.
void set_msh_element_runs(bool on);

} // namespace bisect::testing
