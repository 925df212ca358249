// Format dispatch by extension, input checks shared by all readers, and the
// write-to-temporary-then-rename rule for output (STYLE.md §6).
#include "bisect/io.hpp"
#include "state_arrays.hpp"
#include "vtu_write.hpp"

#include "bisect/check.hpp"
#include "bisect/state.hpp"

#include "bisect/output.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <unistd.h>
#include <vector>

namespace bisect {
namespace {

namespace fs = std::filesystem;

enum class Format { Vtu, Msh };

// The extension of `path` in lower case (".vtu", ".msh", ...).
std::string lower_extension(const std::string &path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// The format named by the (case-insensitive) extension of `path`.
Format format_of(const std::string &path) {
  const std::string lower = lower_extension(path);
  if (lower == ".vtu")
    return Format::Vtu;
  if (lower == ".msh")
    return Format::Msh;
  throw InputError(path, "unknown mesh format '" + fs::path(path).extension().string() +
                             "' (expected .vtu or .msh)");
}

// Fails with a clear reason unless `path` is a readable, non-empty file.
void check_readable_file(const std::string &path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputError(path,
                     "cannot open: " + (ec ? ec.message() : std::string(std::strerror(ENOENT))));
  if (fs::is_directory(st))
    throw InputError(path, "is a directory");
  if (!fs::is_regular_file(st))
    throw InputError(path, "not a regular file (to read a mesh from a pipe, give - as the input "
                           "and send it on standard input)");
  std::FILE *f = std::fopen(path.c_str(), "rb");
  if (!f)
    throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  const bool empty = std::fgetc(f) == EOF;
  std::fclose(f);
  if (empty)
    throw InputError(path, "empty file");
}

// Errors from the writer name the file written into; report them against
// the output's name instead.
std::string strip_prefix(const std::string &what, const std::string &prefix) {
  return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

void write_as(Format format, const std::string &path, const Mesh &mesh, const WriteOptions &options,
              const StateArrays *state = nullptr) {
  if (format == Format::Vtu)
    write_vtu_with_state(path, mesh, options.compression, state);
  else
    write_msh_with_state(path, mesh, state);
}

} // namespace

namespace {

// A triangle mesh off z = 0 (the readers put its z into kPlaneZArray) is
// accepted when it lies in one plane z = c up to 1e-12 of its extent; the
// array then stays (refinement interpolates it, the writers put it back),
// unless every z is 0. Anything less flat is a surface in 3D.
void settle_plane(Mesh &mesh, const std::string &path, Format format) {
  check_names(mesh, path); // every read ends here: names a .vtu can hold (vtu_write.hpp)
  if (mesh.dim != 2)
    return;
  auto it = std::find_if(mesh.point_data.begin(), mesh.point_data.end(),
                         [](const DataArray &a) { return a.name == kPlaneZArray; });
  if (it == mesh.point_data.end() || it->values.empty())
    return;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    const double x[3] = {mesh.point(VertexId(v))[0], mesh.point(VertexId(v))[1], it->values[v]};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], x[k]);
      hi[k] = std::max(hi[k], x[k]);
    }
  }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], std::abs(lo[2]), std::abs(hi[2])});
  if (hi[2] - lo[2] > 1e-12 * extent) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the triangles are not in one plane z = c (z goes from %.17g to %.17g)", lo[2],
                  hi[2]);
    std::string what =
        std::string(buf) + "; bisect refines planar triangle meshes, tetrahedra and 4D meshes";
    if (format == Format::Msh)
      what +=
          " (if these triangles bound a volume, its tetrahedra are missing: is a Physical Volume "
          "missing in the .geo?)";
    throw InputError(path, what);
  }
  if (lo[2] == 0 && hi[2] == 0)
    mesh.point_data.erase(it);
}

} // namespace

// Standard input ("-"): copied into a temporary file (the readers check
// sizes against the file and read it by position), its format told by its
// first byte ('<' XML: .vtu, '$' a Gmsh section: .msh); errors name "-".
static Mesh read_stdin() {
  const char *dir = std::getenv("TMPDIR");
  std::string temp = std::string(dir && *dir ? dir : "/tmp") + "/bisect-stdin-XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0)
    throw InputError("-", "cannot copy standard input to a temporary file in " +
                              std::string(dir && *dir ? dir : "/tmp") + ": " +
                              write_failure(errno));
  struct Remove {
    std::string path;
    int fd;
    ~Remove() {
      if (fd >= 0)
        ::close(fd);
      ::unlink(path.c_str());
    }
  } remove{temp, fd};
  std::vector<char> buf(std::size_t(1) << 20);
  char first = 0;
  for (;;) {
    const ssize_t n = ::read(0, buf.data(), buf.size());
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      throw InputError("-", std::string("cannot read standard input: ") + std::strerror(errno));
    if (n == 0)
      break;
    for (ssize_t i = 0; i < n && !first; ++i)
      if (!std::isspace(static_cast<unsigned char>(buf[std::size_t(i)])) &&
          static_cast<unsigned char>(buf[std::size_t(i)]) < 0x80)
        first = buf[std::size_t(i)];
    for (ssize_t done = 0; done < n;) {
      const ssize_t w = ::write(fd, buf.data() + done, std::size_t(n - done));
      if (w < 0 && errno == EINTR)
        continue;
      if (w < 0)
        throw InputError("-",
                         "cannot copy standard input to " + temp + ": " + write_failure(errno));
      done += w;
    }
  }
  ::close(remove.fd);
  remove.fd = -1;
  if (first != '<' && first != '$')
    throw InputError("-", first ? "standard input is neither a .vtu (XML) nor a .msh file"
                                : "standard input is empty");
  const Format format = first == '<' ? Format::Vtu : Format::Msh;
  Mesh mesh;
  try {
    mesh = format == Format::Vtu ? read_vtu(temp) : read_msh(temp);
  } catch (const InputError &e) {
    throw InputError("-", strip_prefix(e.what(), temp + ": "));
  }
  settle_plane(mesh, "-", format);
  return mesh;
}

Mesh read_mesh(const std::string &path) {
  if (path == "-")
    return read_stdin();
  check_readable_file(path);
  if (lower_extension(path) == ".pvtu") {
    Mesh mesh = read_pvtu(path);
    settle_plane(mesh, path, Format::Vtu);
    return mesh;
  }
  const Format format = format_of(path);
  Mesh mesh = format == Format::Vtu ? read_vtu(path) : read_msh(path);
  settle_plane(mesh, path, format);
  return mesh;
}

Mesh read_mesh(const std::string &path, StoredState &stored) {
  stored = {};
  if (path == "-" || lower_extension(path) != ".vtu")
    return read_mesh(path);
  check_readable_file(path);
  Mesh mesh = read_vtu(path, stored);
  settle_plane(mesh, path, Format::Vtu);
  return mesh;
}

static Format format_named(const std::string &name, const std::string &format) {
  if (format.empty())
    return format_of(name);
  if (format != "vtu" && format != "msh")
    throw InputError(name, "unknown format '" + format + "' (expected vtu or msh)");
  // A name that says .vtu or .msh is not written in the other format (no
  // reader would take the file by its name).
  const std::string ext = lower_extension(name);
  if ((ext == ".vtu" || ext == ".msh") && ext != "." + format)
    throw InputError(name, "the format " + format + " (--format) contradicts the name's " + ext);
  return format == "vtu" ? Format::Vtu : Format::Msh;
}

namespace {

void write_file_as(const std::string &file, const std::string &name, const Mesh &mesh,
                   const WriteOptions &options, const StateArrays *state) {
  const Format format = format_named(name, options.format);
  try {
    write_as(format, file, mesh, options, state);
  } catch (const InputError &e) {
    throw InputError(name, strip_prefix(e.what(), file + ": "));
  } catch (const CheckError &e) {
    throw CheckError(name + ": " + strip_prefix(e.what(), file + ": "));
  }
}

} // namespace

void write_mesh_file(const std::string &file, const std::string &name, const Mesh &mesh,
                     const WriteOptions &options) {
  write_file_as(file, name, mesh, options, nullptr);
}

void write_mesh_file_with_state(const std::string &file, const std::string &name, Mesh &mesh,
                                const WriteOptions &options) {
  if (!mesh.marked()) {
    write_mesh_file(file, name, mesh, options);
    return;
  }
  if (!can_stream_state(mesh)) {
    encode_state(mesh);
    try {
      write_mesh_file(file, name, mesh, options);
    } catch (...) {
      strip_state(mesh);
      throw;
    }
    strip_state(mesh);
    return;
  }
  const StateArrays state = stream_state(mesh, options.orientation);
  write_file_as(file, name, mesh, options, &state);
}

void check_output_format(const std::string &name, int dim, const std::string &format_name) {
  const Format format = format_named(name, format_name);
  if (format == Format::Msh && dim == 4)
    throw InputError(name, "a .msh file cannot hold a 4D mesh; write .vtu");
}

bool prepare_read_mesh(Mesh &mesh, const std::string &path, const LoadProgress &progress,
                       InputFacts &facts, StoredState *stored) {
  // The state's consistency check visits the interior facets, which
  // validation walks anyway: it records them when the file has a state.
  const auto marking = [](const auto &a) { return a.name == kMarkingArray; };
  facts.want_interior =
      std::any_of(mesh.cell_data.begin(), mesh.cell_data.end(), marking) ||
      (stored && std::any_of(stored->cells.begin(), stored->cells.end(), marking));
  prepare_input(mesh, path, progress, &facts);
  if (progress)
    progress("restoring the bisection state", 0.95);
  const bool restored =
      decode_state(mesh, path, facts.want_interior ? &facts.interior : nullptr, stored);
  facts.interior = {};
  return restored;
}

Mesh load_mesh(const std::string &path, const LoadProgress &progress, InputFacts *facts) {
  if (progress)
    progress("reading", 0.0);
  StoredState stored;
  Mesh mesh = read_mesh(path, stored);
  InputFacts local;
  prepare_read_mesh(mesh, path, progress, facts ? *facts : local, &stored);
  return mesh;
}

void save_mesh(const std::string &path, Mesh &mesh, const WriteOptions &options) {
  OutputSet out({}, true);
  const int h = out.add(path);
  write_mesh_file_with_state(out.file(h), path, mesh, options);
  out.commit();
}

void write_mesh(const std::string &path, const Mesh &mesh, const WriteOptions &options) {
  OutputSet out({}, true);
  const int h = out.add(path);
  write_mesh_file(out.file(h), path, mesh, options);
  out.commit();
}

} // namespace bisect
