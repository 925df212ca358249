// The native .vtu writer (vtu_write.cpp): VTK XML UnstructuredGrid with
// inline base64 binary arrays, compressed per 32 KiB block.
#pragma once

#include "bisect/io.hpp"
#include "state_arrays.hpp"

#include <string>

namespace bisect {

using VtuCompression = Compression;

// Writes `mesh` to `path` (created or truncated, written sequentially, so a
// FIFO or a device works). `level` is zlib's compression level (1-9).
// Conventions as io_vtu.cpp: 2D triangles at z = 0, 3D tetrahedra, 4D
// pentatopes as 5-vertex poly-vertex cells with the point array `t` and
// field data SpatialDimension = 4; cell arrays holding only 32-bit integers
// are Int32, other arrays Float64.
// With `state` (stream_state), the bisection state's arrays are written from
// it, and stored arrays it hides are not.
// The names of arrays and physical groups must be text a .vtu attribute
// keeps (is_name_text in text.hpp; VTK reads no cells from a file with one
// that is not): InputError naming `path` and the first that is not. Every
// read checks (io.cpp), and the .vtu writer, for meshes built in memory.
void check_names(const Mesh &mesh, const std::string &path);

void write_vtu_native(const std::string &path, const Mesh &mesh, VtuCompression compression,
                      int level = 1, const StateArrays *state = nullptr);

// write_vtu (io.hpp) with the state's arrays made while writing.
void write_vtu_with_state(const std::string &path, const Mesh &mesh, Compression compression,
                          const StateArrays *state);

} // namespace bisect
