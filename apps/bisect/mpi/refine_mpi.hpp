// bisect refine under mpirun (a BISECT_MPI build; refine_mpi.cpp).
#pragma once

#include "bisect/distributed.hpp"
#include "bisect/io.hpp"
#include "bisect/mesh.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace bisect::cli {

struct DistributedArgs {
  std::string input, region, output, csv; // csv "none": no CSV
  int iterations = 1, depth = 1;
  // --indicator NAME with one rule (IndicatorRule) and its parameter.
  std::string indicator;
  int rule = 0; // IndicatorRule
  double parameter = 0;
  std::optional<Marking> marking;
  std::size_t max_elements = 0; // 0: none
  double max_memory_gib = 0;    // per rank; 0: the memory available, shared by the local ranks
  bool check = false;           // the final check across ranks after every iteration
  Compression compression = Compression::Zlib;
  bool force = false, quiet = false, json = false;
  std::string format;         // --format (with -o -, or a name without .vtu/.msh)
  bool origin = false;        // --origin: bisect:origin, the input cell of each cell
  std::vector<double> slices; // --slices: sections of the gathered mesh (not with .pvtu)
};

struct DistributedCoarsenArgs {
  std::string input, output, region, indicator;
  double below = 0;
  bool all = false, force = false, quiet = false, json = false, check = false;
  int passes = 1;
  std::vector<std::string> sums;
  std::string format;  // --format (with -o -, or a name without .vtu/.msh)
  bool origin = false; // --origin: bisect:origin, the lowest input cell merged into each cell
};

// True when mpirun (or another PMI launcher) started this process.
bool launched_by_mpirun();
// MPI_Init when launched by mpirun; mpi_stop finalises what mpi_start began.
void mpi_start(int *argc, char ***argv);
void mpi_stop();
// MPI_Init when not yet initialised (a .pvtu output without mpirun: one
// rank); mpi_stop finalises it.
void mpi_init_alone();
// The ranks of MPI_COMM_WORLD (1 when MPI is not initialised).
int mpi_world_size();
// The distributed refine: a .pvtu output, or more than one rank.
int run_refine_mpi(const DistributedArgs &args);
// The distributed coarsen (coarsen() of distributed.hpp): the same cases.
int run_coarsen_mpi(const DistributedCoarsenArgs &args);
// Inside a catch block of a distributed command: the exit code for the
// exception being handled. A bisect::Error is thrown on every rank alike
// and said once by rank 0; anything else is one rank's internal error,
// said by that rank, and the job is aborted.
int distributed_exit_code(int rank);
// Whether every rank reads the input's pieces (read_pvtu_parts of
// distributed.hpp): a .pvtu that bisect wrote (it declares bisect:global_id),
// when `allowed`. Rank 0 looks; every rank gets the answer. Collective.
bool pieces_read_in_parallel(const std::string &input, bool allowed, int rank);
// What rank 0 learns of an input it reads, found from the parts instead.
struct PartsFacts {
  int dim = 0;
  std::size_t cells = 0, vertices = 0;
  Invariants whole; // volume and boundary measure (no Euler characteristic)
};
// The parts: from the pieces of `input` when `parallel`, with the checks
// rank 0 makes of an input it reads, on every rank alike (a 4D mesh for a
// gathered .msh `output`, when `gathered`; the region spec against the
// dimension), and `facts` found from them; else distribute(mesh) of what
// rank 0 read (`facts` as the caller set them). Collective; throws on every
// rank.
DistributedMesh input_parts(bool parallel, const Mesh &mesh, const std::string &input, bool origin,
                            bool quiet, bool gathered, const std::string &output,
                            const std::string &format, const std::string &region,
                            PartsFacts &facts);
// Runs `step` on rank 0 (reading and checking the input); its failure (an
// input or check error, or memory) ends every rank: returns the exit code
// on every rank (0: go on), and rank 0 says why in one line. Collective.
int on_rank_zero(int rank, const std::function<void()> &step);

} // namespace bisect::cli
