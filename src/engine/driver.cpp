// The iteration driver (driver.hpp): what `bisect refine` and the library's
// callers run between reading and writing.
#include "bisect/driver.hpp"
#include "bisect/text.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace bisect {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Memory the machine can still give, from /proc/meminfo (0 when unknown).
double available_bytes() {
  std::ifstream f("/proc/meminfo");
  std::string key, unit;
  double kb = 0;
  while (f >> key >> kb >> unit)
    if (key == "MemAvailable:")
      return kb * 1024.0;
  return 0;
}

// The temporary cell array refine_marked tags descendants with.
constexpr const char *kAncestorVolume = "bisect:ancestor_volume";

// A bit per cell of the refined mesh, set for the cells that descend from
// `selected` (ids below `cells_before`; `origin` as RefineLimits::origin
// gives it): an input cell's slot holds its first child.
std::vector<std::uint64_t> descendants(const std::vector<CellId> &selected,
                                       std::size_t cells_before,
                                       const std::vector<CellId> &origin) {
  std::vector<std::uint64_t> was((cells_before + 63) / 64, 0);
  for (CellId c : selected)
    was[c >> 6] |= std::uint64_t(1) << (c & 63);
  const std::size_t nc = cells_before + origin.size(), words = (nc + 63) / 64;
  std::vector<std::uint64_t> out(was);
  out.resize(words, 0);
  const std::size_t first = cells_before / 64;
#pragma omp parallel for num_threads(threads()) schedule(static) if (words - first > (1u << 14))
  for (std::size_t w = first; w < words; ++w) {
    std::uint64_t bits = 0;
    for (std::size_t c = std::max(w * 64, cells_before); c < std::min(nc, w * 64 + 64); ++c) {
      const CellId a = origin[c - cells_before];
      bits |= (was[a >> 6] >> (a & 63) & 1) << (c & 63);
    }
    out[w] |= bits;
  }
  return out;
}

// DriverOptions::cell_data_by_origin: the mesh's cell arrays, kept at the
// input's cells while `root` names each cell's input cell; put back with a
// value per cell when this goes out of scope.
class CellDataByOrigin {
public:
  CellDataByOrigin(Mesh &mesh, bool active) : mesh_(mesh) {
    if (!active || mesh.cell_data.empty())
      return;
    for (const DataArray &a : mesh.cell_data) // one tuple per cell, or left in
      if (a.components < 1 || a.values.size() != mesh.num_cells() * std::size_t(a.components))
        return;
    arrays_ = std::move(mesh.cell_data);
    mesh.cell_data.clear();
    root_.resize(mesh.num_cells());
    for (std::size_t c = 0; c < root_.size(); ++c)
      root_[c] = CellId(c);
    active_ = true;
  }
  CellDataByOrigin(const CellDataByOrigin &) = delete;
  CellDataByOrigin &operator=(const CellDataByOrigin &) = delete;
  // On the way out of run_iterations, also by an exception; if memory runs
  // out rebuilding them, the arrays are dropped rather than left the wrong
  // size.
  ~CellDataByOrigin() {
    try {
      restore();
    } catch (...) {
      mesh_.cell_data.clear();
    }
  }
  bool active() const { return active_; }
  // The values per cell of the arrays held here.
  int components() const {
    int k = 0;
    if (active_)
      for (const DataArray &a : arrays_)
        k += a.components;
    return k;
  }
  // After refine() appended cells from cells_before on, `origin` naming
  // the cell (below cells_before) each descends from.
  void appended(std::size_t cells_before, const std::vector<CellId> &origin) {
    if (!active_ || mesh_.num_cells() == root_.size())
      return; // nothing appended, or undone
    if (cells_before != root_.size() || cells_before + origin.size() != mesh_.num_cells())
      throw CheckError("run_iterations: refine() did not say where its cells descend from");
    root_.resize(cells_before + origin.size());
    const std::size_t n = origin.size();
#pragma omp parallel for num_threads(threads()) schedule(static) if (n > (1u << 16))
    for (std::size_t i = 0; i < n; ++i)
      root_[cells_before + i] = root_[origin[i]];
  }
  void restore() {
    if (!active_)
      return;
    active_ = false;
    const std::size_t nc = mesh_.num_cells();
    root_.resize(nc, 0);
    for (DataArray &a : arrays_) {
      const std::size_t k = std::size_t(a.components);
      std::vector<double> values(nc * k);
#pragma omp parallel for num_threads(threads()) schedule(static) if (nc > (1u << 16))
      for (std::size_t c = 0; c < nc; ++c)
        for (std::size_t j = 0; j < k; ++j)
          values[c * k + j] = a.values[std::size_t(root_[c]) * k + j];
      a.values = std::move(values);
    }
    std::vector<CellId>().swap(root_);
    mesh_.cell_data = std::move(arrays_);
  }

private:
  Mesh &mesh_;
  bool active_ = false;
  std::vector<DataArray> arrays_;
  std::vector<CellId> root_; // per cell: the input cell it descends from
};

// The estimate: each selected cell costs about four new cells with closure,
// and a cell costs its ids, state and arrays twice over while vectors grow.
// `components`: values per cell of cell arrays held outside the mesh
// meanwhile (CellDataByOrigin), counted as if they were in it.
std::string shortfall(const Mesh &mesh, std::size_t selected, double max_gib, int components) {
  double per_cell = 2.5 * (4.0 * (mesh.dim + 1) + 2.0) + 8.0 + 2.0 * 8.0 * components;
  for (const DataArray &a : mesh.cell_data)
    per_cell += 2.0 * 8.0 * a.components;
  // max_gib bounds the whole mesh; otherwise what it adds must fit in the
  // memory available now.
  double need = per_cell * 4.0 * double(selected);
  if (max_gib > 0)
    need += per_cell * double(mesh.num_cells());
  const double avail = max_gib > 0 ? max_gib * 1073741824.0 : available_bytes();
  if (avail <= 0 || need < 0.9 * avail)
    return {};
  char buf[160];
  std::snprintf(buf, sizeof buf, "it would need about %.2f GiB %s, %.2f GiB %s",
                need / 1073741824.0, max_gib > 0 ? "in all" : "more memory", avail / 1073741824.0,
                max_gib > 0 ? "allowed by --max-memory" : "available");
  return buf;
}
} // namespace

std::string memory_shortfall(const Mesh &mesh, std::size_t selected, double max_gib) {
  return shortfall(mesh, selected, max_gib, 0);
}

DriverResult
run_iterations(Mesh &mesh, const Selector &select, const DriverOptions &options,
               const std::function<void(const IterationReport &, Mesh &)> &on_iteration) {
  if (!mesh.marked())
    throw CheckError("run_iterations: the mesh is not marked (ensure_marked)");
  DriverResult result;
  // The invariants every check compares with (the Euler characteristic only
  // for the full check: it is the costly part).
  const Invariants before = options.input_invariants
                                ? *options.input_invariants
                                : measure_invariants(mesh, options.check_every_iteration);
  RefineLimits limits;
  if (options.max_cells)
    limits.max_cells = options.max_cells;
  limits.cancel = options.cancel;
  result.quality = options.input_quality ? *options.input_quality : quality_summary(mesh);
  // The final check's cell pass, taken with the last planned iteration's
  // quality when nothing can change the mesh between the two.
  const bool final_check = options.final_check && !options.check_every_iteration;
  const bool fuse = final_check && (!on_iteration || !options.on_iteration_changes_mesh);
  CellFacts facts;
  // The cells the next selection may pick (DriverOptions::select_among).
  const bool narrow = options.select_among && options.depth <= 1 &&
                      (!on_iteration || !options.on_iteration_changes_mesh);
  std::vector<std::uint64_t> candidates;
  bool have_candidates = false;
  std::vector<CellId> origin;
  if (narrow)
    limits.origin = &origin;
  // Declared after `before`: the invariants are measured with the arrays in.
  CellDataByOrigin by_origin(mesh, options.cell_data_by_origin && options.depth <= 1);
  if (by_origin.active())
    limits.origin = &origin;
  for (int it = 1; it <= options.iterations; ++it) {
    if (options.cancel && options.cancel->load()) {
      result.stop = StopReason::Cancelled;
      break;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<CellId> selected =
        have_candidates ? options.select_among(mesh, candidates) : select(mesh);
    std::vector<std::uint64_t>().swap(candidates);
    have_candidates = false;
    result.select_seconds += seconds_since(t0);
    if (std::string why =
            shortfall(mesh, selected.size(), options.max_memory_gib, by_origin.components());
        !why.empty()) {
      result.stop = StopReason::MemoryLimit;
      result.stop_message = "stopping before iteration " + std::to_string(it) + ": " + why;
      break;
    }
    IterationReport report;
    report.iteration = it;
    report.first_new_vertex = mesh.num_vertices();
    const auto t_refine = std::chrono::steady_clock::now();
    const std::size_t cells_before = mesh.num_cells();
    const RefineResult r = options.depth > 1 ? refine_marked(mesh, selected, options.depth, limits)
                                             : refine(mesh, selected, limits);
    if (narrow && !r.limit_reached && !r.cancelled &&
        origin.size() + cells_before == mesh.num_cells()) {
      candidates = descendants(selected, cells_before, origin);
      have_candidates = true;
    }
    by_origin.appended(cells_before, origin);
    std::vector<CellId>().swap(origin);
    result.refine_seconds += seconds_since(t_refine);
    if (r.cancelled) {
      result.stop = StopReason::Cancelled;
      break;
    }
    if (r.precision_reached) {
      result.stop = StopReason::PrecisionLimit;
      result.stop_message =
          "stopping before iteration " + std::to_string(it) +
          ": it would bisect an edge finer than doubles resolve (extent below 2^-40 of its "
          "coordinates' magnitude, or below 2^-100); writing the mesh after iteration " +
          std::to_string(it - 1);
      break;
    }
    if (r.limit_reached) {
      result.stop = StopReason::CellLimit;
      result.stop_message = "stopping before iteration " + std::to_string(it) + ": it would pass " +
                            (options.max_cells ? "--max-elements " + with_commas(options.max_cells)
                                               : std::string("the 32-bit id limit")) +
                            " (" + with_commas(mesh.num_cells()) + " cells now)";
      break;
    }
    const auto t_quality = std::chrono::steady_clock::now();
    result.quality = fuse && it == options.iterations ? quality_with_cell_facts(mesh, facts)
                                                      : quality_summary(mesh);
    result.quality_seconds += seconds_since(t_quality);
    report.cells = mesh.num_cells();
    report.vertices = mesh.num_vertices();
    report.selected = r.selected;
    report.bisections = r.bisections;
    report.closure_passes = r.closure_passes;
    report.quality = result.quality;
    report.seconds = seconds_since(t0);
    result.bisections += r.bisections;
    result.iterations = it;
    if (on_iteration)
      on_iteration(report, mesh);
    if (options.check_every_iteration) {
      const auto t_check = std::chrono::steady_clock::now();
      const CheckResult c = check_conformity(mesh, &before);
      result.check_seconds += seconds_since(t_check);
      if (!c.ok)
        throw CheckError("after iteration " + std::to_string(it) + ": " + c.failure);
    }
    if (selected.empty()) { // the same would hold for every later iteration
      result.stop = StopReason::NothingSelected;
      break;
    }
  }
  // The final check (--check has checked every iteration in full): whatever
  // went wrong, the caller never gets a non-conforming mesh without an error.
  if (final_check) {
    const auto t_check = std::chrono::steady_clock::now();
#if defined(__GLIBC__)
    // The refinement's freed scratch stays resident in malloc's heap (blocks
    // below its mmap threshold, which glibc raises up to 32 MiB as large
    // blocks are freed). Give those pages back before the check allocates
    // its walk buffers, or both count in the peak (3,178,142 tets: 206 MB
    // resident where the mesh holds 141).
    malloc_trim(0);
#endif
    const CheckResult c = check_refined(mesh, before, &facts);
    result.check_seconds += seconds_since(t_check);
    if (!c.ok)
      throw CheckError("on the refined mesh: " + c.failure);
    if (facts.describe(mesh))
      result.orientation = std::move(facts.signs);
  }
  by_origin.restore();
  return result;
}

// Descendants are told apart by volume: bisection halves a cell's volume, so
// a cell that descends from a marked cell of volume V by g bisections has
// volume V / 2^g (up to rounding, far below a factor 2). The marked cells'
// volume is a temporary cell array, inherited by their children.
RefineResult refine_marked(Mesh &mesh, const std::vector<CellId> &marked, int depth,
                           const RefineLimits &limits) {
  if (depth < 1)
    throw UsageError("refine_marked: depth must be at least 1");
  if (depth == 1 || marked.empty())
    return refine(mesh, marked, limits);
  if (!mesh.marked())
    throw CheckError("refine_marked: the mesh is not marked");
  auto volume = [&](CellId c) {
    double pts[5 * 4];
    cell_points(mesh, c, pts);
    return std::abs(signed_volume(pts, mesh.dim));
  };
  // Undo needs the mesh as it was: the rounds after the first cannot be
  // undone by refine() alone.
  const Mesh saved = mesh;
  mesh.cell_data.push_back({kAncestorVolume, 1, std::vector<double>(mesh.num_cells(), 0.0)});
  std::size_t slot = mesh.cell_data.size() - 1;
  for (CellId c : marked)
    mesh.cell_data[slot].values.at(c) = volume(c);
  RefineResult total;
  std::vector<CellId> round = marked;
  for (int r = 0; r < depth && !round.empty(); ++r) {
    const RefineResult step = refine(mesh, round, limits);
    if (step.limit_reached || step.cancelled) {
      mesh = saved;
      RefineResult undone = step;
      undone.selected = marked.size();
      return undone;
    }
    if (r == 0)
      total.selected = step.selected;
    total.bisections += step.bisections;
    total.closure_passes += step.closure_passes + (r > 0);
    total.kernel_seconds += step.kernel_seconds;
    // The descendants not yet `depth` generations down.
    round.clear();
    slot = std::size_t(std::find_if(mesh.cell_data.begin(), mesh.cell_data.end(),
                                    [](const DataArray &a) { return a.name == kAncestorVolume; }) -
                       mesh.cell_data.begin());
    const std::vector<double> &anc = mesh.cell_data[slot].values;
    for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
      if (anc[c] <= 0)
        continue;
      const double g = std::log2(anc[c] / volume(CellId(c)));
      if (std::lround(g) < depth)
        round.push_back(CellId(c));
    }
  }
  mesh.cell_data.erase(mesh.cell_data.begin() + std::ptrdiff_t(slot));
  return total;
}

} // namespace bisect
