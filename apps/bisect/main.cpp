// The `bisect` command line. Each command is one file of apps/bisect/; this
// one parses, dispatches, and maps errors to exit codes in one place.
#include "cli.hpp"
#ifdef BISECT_MPI
#include "mpi/refine_mpi.hpp"
#endif

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <new>
#include <string>
#include <unistd.h>

using namespace bisect;
using namespace bisect::cli;

namespace {

std::atomic<bool> g_interrupted{false};
// Under mpirun only rank 0 speaks (README, "MPI"): when one rank fails,
// mpirun ends the others with a signal, which they take silently.
bool g_silent_signals = false;
// A rank other than 0 under mpirun: the usage and input errors every rank
// finds alike are printed by rank 0 alone.
bool g_other_rank = false;

// SIGINT, SIGTERM, SIGHUP: before the outputs are committed nothing of the
// run's result exists but temporary files, so they are removed and the
// process ends at once, whatever it was doing (reading, refining, writing).
// After the commit the run is complete and the signal is only noted.
// (Whichever thread takes the signal: remove_pending_outputs decides, once,
// between this and the commit.)
extern "C" void on_signal(int) {
  if (!remove_pending_outputs()) {
    g_interrupted = true;
    return;
  }
  static const char msg[] = "bisect: interrupted; no output written\n";
  if (!g_silent_signals)
    (void)!::write(STDERR_FILENO, msg, sizeof msg - 1);
  ::_exit(kExitInterrupted);
}

void install_signal_handlers() {
  for (const char *v : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char *rank = std::getenv(v); rank && std::string(rank) != "0")
      g_silent_signals = g_other_rank = true;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP})
    ::sigaction(sig, &sa, nullptr);
  // A file size limit or a reader that went away makes write() fail with
  // EFBIG or EPIPE, reported as such, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  std::signal(SIGPIPE, SIG_IGN);
}

} // namespace

int run(int argc, char **argv);

namespace {
// A stream that writes nowhere.
std::ostream &discard() {
  static std::ostream none(nullptr);
  return none;
}
} // namespace

int main(int argc, char **argv) {
#ifdef BISECT_MPI
  // Under mpirun every rank runs the command (README, "MPI").
  mpi_start(&argc, &argv);
  const int code = run(argc, argv);
  // The run has said how it ended: mpirun may end the other ranks (and this
  // one, while it finalises) with a signal when some rank's code is not 0.
  g_silent_signals = true;
  mpi_stop();
  return code;
#else
  // mpirun starting copies of a build without MPI: each would run the whole
  // job and write the same files. Refused, said once (by the first copy).
  for (const char *size : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char *n = std::getenv(size); n && std::atoi(n) > 1) {
      const char *rank = std::getenv("OMPI_COMM_WORLD_RANK");
      if (!rank)
        rank = std::getenv("PMI_RANK");
      if (!rank || std::atoi(rank) == 0)
        std::cerr << "bisect: mpirun started " << n
                  << " copies of a bisect built without MPI, each of which would run the whole "
                     "job: use the MPI build (cmake -DBISECT_MPI=ON; scripts/test.sh makes "
                     "build-mpi/bisect)\n";
      return 1;
    }
  return run(argc, argv);
#endif
}

int run(int argc, char **argv) {
  install_signal_handlers();

  CLI::App app{"bisect: conformal local refinement of triangle, tetrahedral and 4D simplicial "
               "meshes by edge bisection (Maubach / Arnold-Mukherjee-Pouly marking, seeds "
               "000-002)."};
  app.footer(kExitCodesHelp);
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("bisect ") + BISECT_VERSION);

  std::vector<Command> commands{add_refine(app),  add_info(app),   add_check(app),
                                add_quality(app), add_colour(app), add_extrude(app),
                                add_slice(app),   add_coarsen(app)};
  for (Command &c : add_generate(app))
    commands.push_back(std::move(c));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion &e) {
    return app.exit(e);
  } catch (const CLI::ParseError &e) {
    // CLI11 says "A subcommand is required" for a misspelt command.
    std::string names;
    bool known = false;
    for (const CLI::App *sub : app.get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known |= argc > 1 && sub->get_name() == argv[1];
    }
    if (g_other_rank)
      return kExitInput;
    if (argc > 1 && argv[1][0] != '-' && !known) {
      std::cerr << "bisect: unknown command '" << argv[1] << "' (commands: " << names << ")\n";
      return kExitInput;
    }
    std::cerr << "bisect: " << e.what() << " (see bisect --help)\n";
    return kExitInput;
  }

  try {
    for (const Command &c : commands)
      if (*c.app)
        return c.run();
  } catch (const Error &e) {
    // (Every rank meets these alike: rank 0 speaks for all.)
    std::ostream &err = g_other_rank ? discard() : std::cerr;
    switch (e.kind) {
    case ErrorKind::Check:
      err << "bisect: internal check failed: " << one_line(e.what()) << "\n";
      return kExitCheck;
    case ErrorKind::Limit:
      err << "bisect: " << one_line(e.what()) << "\n";
      return kExitLimit;
    case ErrorKind::Input:
    case ErrorKind::Usage:
    case ErrorKind::Resource:
      err << "bisect: " << one_line(e.what()) << "\n";
      return kExitInput;
    }
  } catch (const std::bad_alloc &) {
    std::cerr << "bisect: out of memory; no output written (try --max-elements)\n";
    return kExitMemory;
  } catch (const std::exception &e) {
    std::cerr << "bisect: internal error: " << one_line(e.what()) << "\n";
    return kExitCheck;
  }
  return kExitOk;
}
