// Times the final check (check_refined) alone on a saved mesh: the part of
// `bisect refine` that stages.final_check reports, without the run around it.
//
//   bisect_check_bench FILE [REPEATS=8] [THREADS=1]
//
// Reads FILE, measures its invariants, then runs check_refined REPEATS times
// against them and prints one JSON object: cells, best and mean seconds,
// nanoseconds per cell, threads, and the machine's load before the runs.
// Then what `bisect refine` runs: the last iteration's quality pass with
// the check's cell facts (quality_with_cell_facts) against the plain one
// (quality_summary), and the check given those facts; "in_run_seconds" is
// the check's cost in a run: the fused pass's extra time plus that check
// (best of each).
#include "bisect/bisect.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

int main(int argc, char **argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: bisect_check_bench FILE [REPEATS=8] [THREADS=1]\n");
    return 2;
  }
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 8;
  const int threads = argc > 3 ? std::max(1, std::atoi(argv[3])) : 1;
  try {
    bisect::Mesh mesh = bisect::read_mesh(argv[1]);
    bisect::set_threads(threads);
    const bisect::Invariants original = bisect::measure_invariants(mesh, false);
    std::string load;
    std::getline(std::ifstream("/proc/loadavg"), load);
    double best = 1e300, total = 0;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const bisect::CheckResult c = bisect::check_refined(mesh, original);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!c.ok) {
        std::fprintf(stderr, "bisect_check_bench: %s: %s\n", argv[1], c.failure.c_str());
        return 1;
      }
      best = std::min(best, s);
      total += s;
    }
    // Best of `repeats` of f().
    auto best_of = [&](auto f) {
      double b = 1e300;
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        b = std::min(b,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      return b;
    };
    bisect::CellFacts facts;
    const double plain = best_of([&] { bisect::quality_summary(mesh); });
    const double fused = best_of([&] { bisect::quality_with_cell_facts(mesh, facts); });
    bool ok = true;
    const double with_facts =
        best_of([&] { ok &= bisect::check_refined(mesh, original, &facts).ok; });
    if (!ok) {
      std::fprintf(stderr, "bisect_check_bench: %s: the check with cell facts failed\n", argv[1]);
      return 1;
    }
    std::printf("{\"file\": \"%s\", \"cells\": %zu, \"threads\": %d, \"repeats\": %d, "
                "\"best_seconds\": %.4f, \"mean_seconds\": %.4f, \"best_ns_per_cell\": %.1f, "
                "\"quality_seconds\": %.4f, \"fused_quality_seconds\": %.4f, "
                "\"check_with_facts_seconds\": %.4f, \"in_run_seconds\": %.4f, "
                "\"load_before\": \"%.14s\"}\n",
                argv[1], mesh.num_cells(), threads, repeats, best, total / repeats,
                best / double(mesh.num_cells()) * 1e9, plain, fused, with_facts,
                fused - plain + with_facts, load.c_str());
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bisect_check_bench: %s\n", e.what());
    return 1;
  }
}
