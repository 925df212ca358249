// bisect refine under mpirun (a BISECT_MPI build; refine_mpi.cpp).
#pragma once

#include "bisect/io.hpp"
#include "bisect/mesh.hpp"

#include <optional>
#include <string>

namespace bisect::cli {

struct DistributedArgs {
  std::string input, region, output, csv; // csv "none": no CSV
  int iterations = 1, depth = 1;
  // --indicator NAME with one rule (IndicatorRule) and its parameter.
  std::string indicator;
  int rule = 0; // IndicatorRule
  double parameter = 0;
  std::optional<Marking> marking;
  Compression compression = Compression::Zlib;
  bool force = false, quiet = false, json = false;
};

// True when mpirun (or another PMI launcher) started this process.
bool launched_by_mpirun();
// MPI_Init when launched by mpirun; mpi_stop finalises what mpi_start began.
void mpi_start(int *argc, char ***argv);
void mpi_stop();
// The ranks of MPI_COMM_WORLD (1 when MPI is not initialised).
int mpi_world_size();
// The distributed refine: a .pvtu output, or more than one rank.
int run_refine_mpi(const DistributedArgs &args);

} // namespace bisect::cli
