// Test hooks of the checks (not part of the installed API).
#pragma once

#include "bisect/mesh.hpp"

#include <cstddef>
#include <vector>

namespace bisect::testing {

// The final check (check_refined) matches most facets by hashing within the
// walk's coarse buckets and falls back to the sorted walk where it finds a
// defect. With `on`, it takes the sorted walk everywhere, so a test can
// compare the two: they must give the same verdict and message.
void use_sorted_final_walk(bool on);

// The hashing splits a coarse bucket into pieces of about `entries` facets
// (0: the default, 2048); a small value makes test meshes take the split.
void set_final_walk_piece(std::size_t entries);

// The walks' buffer budget in bytes (0: their own, up to 96 MiB, 160 for
// the final check); a small one splits test meshes into several chunks.
void set_walk_chunk_bytes(std::size_t bytes);

// With `on`, the final check never packs a facet's place in its coarse
// bucket into its entry (FineInKey, see final_facet_pass in check.cpp) and
// takes the wider packing it uses for larger meshes instead.
void use_wide_final_walk(bool on);

// In 3D the facet walk of validation and the checks packs a facet into 8
// bytes (its cell without the facet's number) where the ids are narrow
// enough (CellRefs, see Walk in check.cpp); with `on` false it always takes
// the 16-byte packing, so a test can compare the two.
void use_narrow_facet_walk(bool on);
// Whether the 4D angle check walks all triangles of all cells (FoldVisitor)
// instead of finding each from its smallest vertex's star (the default).
// Both must give the same faces count, findings and skipped faces.
void use_walk_fold4(bool on);

// The overlap search (find_overlap in check.cpp) reads a small grid per
// group of cells; with `on`, every cell makes its own range search instead
// (what a cell at a group's edge does), so a test can compare the two.
void use_own_overlap_search(bool on);

// Before the overlap search, prepare_input counts the boundary facets a ray
// from each centroid passes (centroids_wound_once in check.cpp) and skips
// the search when every count is surely 1. With `on` false it never does;
// overlap_fast_path_taken() tells whether the last count was sure.
void use_overlap_fast_path(bool on);
bool overlap_fast_path_taken();

// When the count was sure, the angle check skips the faces where it is
// surely 1 all around (find_fold in check.cpp); with `out`, each skipped
// face's sorted vertex ids are appended there (null: not recorded).
void record_skipped_faces(std::vector<std::vector<VertexId>> *out);

// The angle check's quick atan2(y, x) for y >= 0 (rough_angle in check.cpp),
// which must stay within 2e-5 of std::atan2 for its shortcut to be safe.
double rough_angle(double y, double x);

} // namespace bisect::testing
