// Native reader of VTK XML unstructured grid files (.vtu): the XML subset
// VTK and meshio write, and the array encodings (ascii, inline base64,
// appended raw or base64; uncompressed, zlib, lz4 or lzma). No VTK code is
// involved, so a corrupt file can only end in an InputError.
//
// The result is the file's content, pieces concatenated (point ids offset
// per piece, as VTK does); which cells make the mesh is decided by the
// caller (io_vtu.cpp).
#pragma once

#include "bisect/state.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace bisect::vtu {

// A numeric DataArray as doubles (what vtkDataArray::GetComponent gives).
// Non-numeric arrays (String, Bit) keep their place, name and no values, so
// that unnamed arrays are numbered as VTK numbers them.
struct Array {
  std::string name; // as in the file; may be empty
  int components = 1;
  bool numeric = true;
  std::vector<double> values; // tuples * components, component fastest
  std::string type;           // as in the file: "Int32", "Float64", ...
  // Read in the file's own integer type into `ints` instead of `values`
  // (read_grid's `keep_state_types`, for the arrays StoredState holds).
  bool stored = false;
  decltype(StoredArray::values) ints;
};

struct Grid {
  std::size_t num_points = 0;
  std::size_t num_cells = 0;
  std::vector<double> points;              // x, y, z per point
  std::vector<std::uint32_t> connectivity; // point ids (< num_points) of all cells
  std::vector<std::int64_t> offsets;       // num_cells entries, each cell's end: cell c uses
                                           // connectivity[begin(c), offsets[c]) (the
                                           // file's own array, not copied: 8 bytes a cell)
  std::vector<std::uint8_t> types;         // VTK cell type per cell
  std::vector<Array> point_data, cell_data, field_data;
  std::int64_t begin(std::size_t c) const { return c ? offsets[c - 1] : 0; }
};

// Reads `path`; throws InputError(path, one line) on anything it cannot
// read exactly.
// With `keep_state_types`, the arrays a StoredState holds (by name; Int8,
// UInt8, Int16, UInt16 or Int32; one piece only) are read as Array::ints.
Grid read_grid(const std::string &path, bool keep_state_types = false);

// Same, from bytes already in memory (`path` only names them in errors).
Grid parse_grid(const std::string &path, const char *data, std::size_t size,
                bool keep_state_types = false);

} // namespace bisect::vtu
