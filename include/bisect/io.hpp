// Reading and writing meshes. The format is chosen by the file extension:
// `.vtu` (VTK XML unstructured grid) and `.msh` (Gmsh 2.2 and 4.1).
#pragma once

#include "bisect/check.hpp"
#include "bisect/mesh.hpp"
#include "bisect/state.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace bisect {

// Reads the cells of the highest dimension present (triangles -> 2D when all z
// are 0, tetrahedra -> 3D, pentatopes in the 4D .vtu convention -> 4D). A
// .pvtu is read as one mesh (read_pvtu).
// Cells are returned in file order (.msh: in element tag order), unmarked
// (mesh.stage empty). Cell data and
// point data become DataArrays; Gmsh tags become cell arrays
// "gmsh:physical" and "gmsh:geometrical". Throws InputError naming the file.
Mesh read_mesh(const std::string &path);
// The same, except that a one-piece .vtu's bisection state arrays go into
// `stored` in their file types (StoredState in state.hpp), not into the
// mesh's DataArrays: for prepare_read_mesh, in less memory. Other files
// leave `stored` empty.
Mesh read_mesh(const std::string &path, StoredState &stored);

// How a mesh is written.
enum class Compression { None, Zlib, Lz4 };
struct WriteOptions {
  std::string format;                          // "vtu" or "msh"; empty: by the name's extension
  Compression compression = Compression::Zlib; // .vtu arrays (ParaView reads all three)
  // The sign of every cell's volume (+1, -1) in the mesh as it is written,
  // when the caller knows them (DriverResult::orientation): a marked .vtu
  // then orients its cells by them instead of computing every cell's volume
  // again. Ignored unless it has a value per cell.
  const std::vector<std::int8_t> *orientation = nullptr;
};

// Writes `mesh` as given (cells in their stored vertex order) to `path`,
// through a temporary file in the same directory renamed when complete (an
// OutputSet of one, see output.hpp: links are written through, a FIFO or
// device is written into).
void write_mesh(const std::string &path, const Mesh &mesh, const WriteOptions &options = {});

// Writes `mesh` into the file `file` (created or truncated) in
// `options.format` ("vtu" or "msh"), or when that is empty in the format
// named by the extension of `name`; errors name `name`. For OutputSet users.
void write_mesh_file(const std::string &file, const std::string &name, const Mesh &mesh,
                     const WriteOptions &options = {});
// write_mesh_file for a mesh whose bisection state (a marked mesh's bisect:*
// arrays, state.hpp) must go with it, as encode_state + write_mesh_file +
// strip_state: the mesh is as before on return, also after an exception.
// The .vtu writer makes the state's arrays value by value while writing
// instead of storing them in the mesh first (24 bytes per tet less at the
// write's memory peak).
void write_mesh_file_with_state(const std::string &file, const std::string &name, Mesh &mesh,
                                const WriteOptions &options = {});

// Checks that `format` (or, when empty, the extension of `name`, any case)
// is one the writer knows, and that a mesh of dimension `dim` fits it
// (.msh holds no 4D mesh; dim 0: not known yet).
void check_output_format(const std::string &name, int dim, const std::string &format = {});

// Reads `path` ready to refine: validated (see prepare_input in check.hpp;
// InputError naming the file), every cell positively oriented, and the
// bisection state restored when the file carries one (then mesh.marked();
// otherwise the mesh is unmarked: see ensure_marked in mark.hpp).
// `progress`, when set, hears of each step (see LoadProgress in check.hpp).
// `facts`, when given, receives what validation found (InputFacts in
// check.hpp: the invariants, so that they need not be measured again).
Mesh load_mesh(const std::string &path, const LoadProgress &progress = {},
               InputFacts *facts = nullptr);

// What load_mesh does after the read, for a caller that read `mesh` from
// `path` itself (read_mesh): validates it and restores its bisection state,
// walking its facets once (the state's consistency check takes the interior
// facets validation found). Returns whether the mesh carried a state
// (decode_state in state.hpp). `facts` receives the invariants. `stored`:
// what read_mesh(path, stored) kept apart (emptied).
bool prepare_read_mesh(Mesh &mesh, const std::string &path, const LoadProgress &progress,
                       InputFacts &facts, StoredState *stored = nullptr);

// Writes `mesh` with its bisection state (the bisect:* cell arrays, so that
// refining the file continues the same sequence) through a temporary file
// renamed when complete. The mesh is the same when it returns.
void save_mesh(const std::string &path, Mesh &mesh, const WriteOptions &options = {});

// Format-specific entry points (used by read_mesh/write_mesh and the tests).
Mesh read_msh(const std::string &path);
void write_msh(const std::string &path, const Mesh &mesh);
Mesh read_vtu(const std::string &path);
Mesh read_vtu(const std::string &path, StoredState &stored); // see read_mesh
// A .pvtu (what a distributed refine writes, or ParaView): its pieces read
// as .vtu files and merged into one mesh (read_mesh takes .pvtu too). Points
// in several pieces become one vertex: by the point array bisect:global_id
// (state.hpp) where the pieces carry it, else by their coordinates; vertices
// with ids come first, by id, then the others by coordinates. A tagged
// lower-dimensional cell in several pieces is kept once. The pieces' tree
// arrays (bisect:parent_a and the like, which name a piece's own points) are
// dropped: a mesh read from a .pvtu has no tree.
Mesh read_pvtu(const std::string &path);
// The pieces a .pvtu names, as paths (relative ones beside the .pvtu), in
// their order; InputError naming `path` when it is no .pvtu index.
std::vector<std::string> pvtu_pieces(const std::string &path);
// The point arrays a .pvtu declares (its <PPointData> names): a parallel
// read (distributed.hpp) looks for bisect:global_id before any piece.
std::vector<std::string> pvtu_point_arrays(const std::string &path);
void write_vtu(const std::string &path, const Mesh &mesh,
               Compression compression = Compression::Zlib);

} // namespace bisect
