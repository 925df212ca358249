// Format dispatch by extension, input checks shared by all readers, and the
// write-to-temporary-then-rename rule for output (STYLE.md §6).
#include "io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace bisect {
namespace {

namespace fs = std::filesystem;

enum class Format { Vtu, Msh };

// The format named by the (case-insensitive) extension of `path`.
Format format_of(const std::string &path) {
  std::string ext = fs::path(path).extension().string();
  std::string lower = ext;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (lower == ".vtu")
    return Format::Vtu;
  if (lower == ".msh")
    return Format::Msh;
  throw InputError(path, "unknown mesh format '" + ext + "' (expected .vtu or .msh)");
}

// Fails with a clear reason unless `path` is a readable, non-empty file.
void check_readable_file(const std::string &path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputError(path, "cannot open: " +
                               (ec ? ec.message() : std::string(std::strerror(ENOENT))));
  if (fs::is_directory(st))
    throw InputError(path, "is a directory");
  if (!fs::is_regular_file(st))
    throw InputError(path, "not a regular file");
  std::FILE *f = std::fopen(path.c_str(), "rb");
  if (!f)
    throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  const bool empty = std::fgetc(f) == EOF;
  std::fclose(f);
  if (empty)
    throw InputError(path, "empty file");
}

// ".<name>.tmp<pid><ext>" beside the target: same directory (so rename is
// atomic) and same extension (so writers that look at it still work).
std::string temporary_name(const std::string &path) {
  const fs::path p(path);
  std::string name = ".";
  name += p.stem().string();
  name += ".tmp";
  name += std::to_string(::getpid());
  name += p.extension().string();
  return (p.parent_path() / name).string();
}

// Errors from the writer name the temporary file; report them against the
// target instead.
std::string strip_prefix(const std::string &what, const std::string &prefix) {
  return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

void write_as(Format format, const std::string &path, const Mesh &mesh) {
  if (format == Format::Vtu)
    write_vtu(path, mesh);
  else
    write_msh(path, mesh);
}

} // namespace

Mesh read_mesh(const std::string &path) {
  check_readable_file(path);
  return format_of(path) == Format::Vtu ? read_vtu(path) : read_msh(path);
}

void write_mesh(const std::string &path, const Mesh &mesh) {
  const Format format = format_of(path);
  const std::string tmp = temporary_name(path);
  auto remove_tmp = [&] {
    std::error_code ignored;
    fs::remove(tmp, ignored);
  };
  try {
    write_as(format, tmp, mesh);
  } catch (const InputError &e) {
    remove_tmp();
    throw InputError(path, strip_prefix(e.what(), tmp + ": "));
  } catch (const CheckError &e) {
    remove_tmp();
    throw CheckError(path + ": " + strip_prefix(e.what(), tmp + ": "));
  } catch (...) {
    remove_tmp();
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    remove_tmp();
    throw InputError(path, std::string("cannot write: ") + std::strerror(err));
  }
}

} // namespace bisect
