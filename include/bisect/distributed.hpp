// Distributed refinement on MPI (built with -DBISECT_MPI=ON; the library
// bisect::mpi). Each rank holds a part of the mesh (the cells of one stretch
// of a Hilbert curve through the cell centroids) and refines it with the
// serial engine; the edges a part bisects on its border are sent to the
// parts that share them, which bisect them too, until no part changes.
// Because every mark follows from the marking of the whole input, the union
// of the parts is the serial run's mesh, for every number of ranks (README,
// "MPI").
//
// Vertices are known across ranks by their coordinates: a midpoint is
// computed from its edge's ends in the same way on every rank, so equal
// coordinates name the same vertex, exactly, with no id to agree on.
#pragma once

#include "bisect/check.hpp"
#include "bisect/coarsen.hpp"
#include "bisect/io.hpp"
#include "bisect/measure.hpp"
#include "bisect/mesh.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"

#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bisect {

// An MPI communicator this code made and frees.
class Communicator {
public:
  Communicator() = default;
  explicit Communicator(MPI_Comm c) : c_(c) {}
  ~Communicator();
  Communicator(Communicator &&o) noexcept : c_(o.c_) { o.c_ = MPI_COMM_NULL; }
  Communicator &operator=(Communicator &&o) noexcept;
  Communicator(const Communicator &) = delete;
  Communicator &operator=(const Communicator &) = delete;
  MPI_Comm get() const { return c_; }

private:
  MPI_Comm c_ = MPI_COMM_NULL;
};

struct DistributedMesh {
  Communicator comm;  // every rank (a duplicate of the communicator given)
  Communicator graph; // the ranks sharing a vertex with this one (neighbours)
  int rank = 0, size = 1;
  // This rank's cells, with their bisection state, cell and point data. Its
  // input vertices come first, in increasing input id (so that the global
  // edge order of the marking compares them as in the whole mesh), then the
  // vertices refinement made. The tree (mesh.hpp) is kept where it is
  // local: a vertex whose parents are in another part has kNoVertex parents
  // here (the root keeps the input's tree for gather()).
  Mesh local;
  std::vector<std::uint64_t> input_vertex; // per input vertex of `local`: its id in the input
  // Per vertex of `local`: the other ranks that may hold it (sorted). A
  // superset: a vertex made on an edge gets the ranks both ends have.
  std::vector<std::vector<int>> sharers;
  std::vector<int> neighbours; // sorted: every rank in some sharers list
  // When the input had a tree: for the first parent_points.size() / (2 dim)
  // vertices of `local` (those it had when the part was made or last
  // migrated), the coordinates of the two ends of their parent edge, 2 dim
  // doubles each (NaN for an original vertex): a part may lack a vertex's
  // parents, and these name them, for the tree of a .pvtu's pieces
  // (write_pvtu) and for gather().
  std::vector<double> parent_points;
  // On the root, when distribute() was given a mesh with a tree: its
  // parent_edge and level (empty after read_pvtu_parts or coarsen(): gather()
  // then takes the input vertices' tree from the parts).
  std::vector<VertexId> input_parent_edge;
  std::vector<std::uint16_t> input_level;
  std::size_t global_cells = 0, global_vertices = 0;
};

// Splits `mesh` (significant on `root` only: a marked mesh with no tagged
// lower-dimensional entities) among the ranks of `comm`: cells sorted along
// a Hilbert curve through their centroids, in equal stretches. Collective.
// Throws CheckError (on every rank) when the input has fewer cells than
// there are ranks or carries entities.
DistributedMesh distribute(const Mesh &mesh, int root, MPI_Comm comm);

// What read_pvtu_parts can add while it reads.
struct PartsReadOptions {
  LoadProgress progress; // hears of the first piece's load on rank 0 (LoadProgress, check.hpp)
  bool origin = false;   // add bisect:origin: each cell's index in read_pvtu's order of cells
};

// Whether read_pvtu_parts can read the .pvtu `path`: it declares the point
// array bisect:global_id (bisect's write_pvtu wrote it). Reads the index only.
bool pvtu_has_global_ids(const std::string &path);

// Reads the .pvtu `path` with its pieces spread over the ranks of `comm`:
// with K pieces, rank r loads pieces [rK/P, (r+1)K/P), each validated as an
// input file (load_mesh), merges them by coordinates, and the cells then
// migrate to equal stretches of the Hilbert curve, as rebalance() moves them;
// no rank holds more than its pieces and its new part. Where pieces meet,
// the stars of the vertices with cells of two pieces around them are
// validated together (prepare_input and the state's consistency: a facet
// in three cells, a hanging node or a state that disagrees across a facet
// between pieces is refused like one within a piece). The pieces must carry
// bisect:global_id (dense: the ids 0..N-1 once each) and the bisection
// state, and not explicit marking; the tree's bisect:piece_* arrays when
// present. The result is what distribute() gives for read_pvtu's mesh,
// up to the parts' cuts and the numbering of vertices made since the run
// that wrote the pieces began. Collective; an error is thrown on every rank
// alike (the lowest failing rank's).
DistributedMesh read_pvtu_parts(const std::string &path, MPI_Comm comm,
                                const PartsReadOptions &options = {});

// The whole mesh's invariants from its parts (collective): volumes summed,
// and the boundary measure less every part's border with other parts.
Invariants whole_invariants(const DistributedMesh &d);

struct DistributedRefineResult {
  std::size_t selected = 0, bisections = 0; // over all ranks
  int rounds = 0;                           // exchanges that made some rank bisect more
  std::size_t edges_sent = 0;               // edges this rank sent (each 2 dim doubles)
  double exchange_seconds = 0;              // this rank, in communication
  bool precision_reached = false;           // some rank stopped at the precision
                                            // limit; the parts are then not usable
};

// Bisects the cells `selected` (ids of d.local) and refines to conformity
// across all ranks. Collective. `limits` go to each part's refine(): with
// `cancel` set (to a flag that stays false) every part keeps its undo log,
// so that the precision limit undoes that part's last step and sets
// precision_reached instead of throwing; the parts are then not usable
// (keep a copy to go back to). A part whose refine() throws makes every
// rank throw CheckError naming it.
DistributedRefineResult refine(DistributedMesh &d, const std::vector<CellId> &selected,
                               const RefineLimits &limits = {});

// select_cells (region.hpp) on every part, collective: the same cells the
// whole mesh would select. A region whose filter ranks the cells (the
// levelset indicator, Region::filter_ranks_cells) ranks them over all parts
// (every rank receives the scores of all touched cells, 8 bytes each).
std::vector<CellId> select_cells(const DistributedMesh &d, const Region &region);

// refine_marked (driver.hpp) across ranks: each marked cell `depth`
// generations down, then to conformity. Collective.
DistributedRefineResult refine_marked(DistributedMesh &d, const std::vector<CellId> &marked,
                                      int depth, const RefineLimits &limits = {});

// Global figures (collective): quality over all cells; cells and vertices
// (shared vertices counted once).
QualitySummary quality_summary(const DistributedMesh &d);
void count_global(DistributedMesh &d);

// The final check across ranks (collective; the same answer on every rank):
// check_refined (check.hpp) on each part against the part's own invariants
// as distributed (`part_original`: refinement keeps a part's volume and
// boundary measure, the boundary with other parts included), then the
// border between parts: the facets a part has alone there, matched by their
// vertices' coordinates against its neighbours', must cover what
// border_measure() gave when the parts were made (`border_original`). A facet
// split on one side only leaves halves that match nothing, so the matched
// measure falls short. Only border cells are looked at beyond the part's own
// check.
CheckResult check_refined(const DistributedMesh &d, const Invariants &part_original,
                          double border_original);
// The measure of this part's border with other parts (collective).
double border_measure(const DistributedMesh &d);

// The whole mesh on `root` (elsewhere an empty mesh), with its tree: input
// vertices in input order, then the made ones by level (the iteration that
// made them), then after their parents, then in lexicographic order of their
// coordinates; cells in increasing order of their sorted vertex ids. So the
// gathered mesh is the same file for every number of ranks. Collective.
Mesh gather(const DistributedMesh &d, int root);

// The largest part's cells over the mean (1: balanced). Collective.
double imbalance(const DistributedMesh &d);
// When the largest part exceeds the mean by more than `tolerance` (0.1:
// 10%), makes the parts again along the Hilbert curve through all parts'
// cells as they are now (equal stretches, splitters found with all-reduces)
// and migrates the cells there, rank to rank, with their state, tree, tags
// and data; who shares which vertex is found again through a directory (each
// vertex at a home rank its coordinates hash to). Returns whether it did.
// Collective. No rank holds the whole mesh (only its old and new parts). The parts pass
// check_refined(d, part_original, border_original) first, else CheckError
// on every rank; the parts' own invariants and border_measure() must then be
// taken again. Explicit marking keeps its parts (its edge ranks do not
// travel).
bool rebalance(DistributedMesh &d, const Invariants &part_original, double border_original,
               double tolerance = 0.1);

// coarsen() (coarsen.hpp) across ranks: `marks` has one entry per cell of
// d.local (non-zero: may be merged away). Collective. Every part coarsens its
// own cells; no rank gathers the mesh. Each pass first finds the vertices
// the whole mesh's pass would consider (made, no newer vertex in their star
// on any part), then runs in rounds: each part runs the serial pass among
// those no other part holds (every cell around them is here); then the
// cells around each such vertex still on a border (its cells here all
// marked and made by bisection) move to the lowest rank holding it, and the
// parts run again, until no cell moves (cells only move to lower ranks, so
// the rounds end). A pass's outcome does not depend on the order its
// vertices go in, so the result is the serial coarsening's for every number
// of ranks (cells as sets of coordinates). Between passes and at the end,
// parts more than 10% above the mean are made again along the Hilbert
// curve; the input ids of the vertices left are made 0..N-1 again (the
// root's copy of the input's tree is dropped: gather() takes the tree from
// the parts). `on_pass` is called on rank 0 with the whole mesh's figures.
// The parts' own invariants and border_measure() must then be taken again.
// Throws UsageError for explicit marking (its edge ranks do not travel).
CoarsenResult coarsen(DistributedMesh &d, const std::vector<char> &marks,
                      const CoarsenOptions &options = {},
                      const std::function<void(const CoarsenPass &)> &on_pass = {});

// Writes `path` (.pvtu) on rank 0 and one piece per rank beside it,
// <stem>_<rank>.vtu, with the bisection state and the tree (its parents
// named by coordinates, as a piece may lack them: the bisect:piece_* arrays
// of state.hpp, which read_pvtu turns back into the tree, so a .pvtu can be
// coarsened): VTK's parallel reader (the one ParaView uses) reads it. Every file is written to a
// temporary name and renamed only when all ranks have written theirs. Existing files are replaced
// only with `force`. Collective; throws InputError on every rank when some rank failed.
void write_pvtu(const std::string &path, DistributedMesh &d, bool force,
                const WriteOptions &options = {});

} // namespace bisect
