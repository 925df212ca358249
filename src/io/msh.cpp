// Gmsh .msh files: reading MSH 2.2 and 4.1 (ASCII and binary), writing
// MSH 4.1 binary.
//
// Format reference: the Gmsh manual, section "MSH file format" (versions 4.1
// and 2.2). Facts this file relies on:
//  - `$MeshFormat` gives "version file-type data-size"; a binary file follows
//    it with the int 1 written in the machine's byte order.
//  - 2.2 binary: node = int tag + 3 doubles; elements come in blocks headed by
//    three ints (type, count, number of tags), each element being
//    int tag, int tags[], int nodes[].
//  - 4.1 binary: counts and tags are size_t (data-size bytes), entity
//    dimensions/tags and element types are int; nodes come in entity blocks
//    (all tags, then all coordinates).
//  - $NodeData/$ElementData: string, real and integer tags in ASCII
//    (integer tags: time step, components, number of entries), then entries
//    "int tag, double values[components]" (binary in binary files).
//
// The reader keeps the linear simplices of the highest dimension as cells,
// and the lower-dimensional linear simplices of physical groups as tagged
// entities (mesh.hpp; add_entities), with $PhysicalNames; everything
// it rejects is reported as InputError(path, "line N: ...") for ASCII files
// and "byte offset N: ..." for binary ones. A count read from the file never
// reserves more than the rest of the file can hold, and every loop it drives
// consumes input, so a corrupted count ends in an error where the data runs
// out instead of in a huge allocation or a long loop.
//
// Gmsh tags become the cell arrays "gmsh:physical" and "gmsh:geometrical":
// in 2.2 the first two element tags (when elements carry two tags); in 4.1
// the element block's entity tag and that entity's first physical tag in
// $Entities (when the file has $Entities; "gmsh:physical" only when some
// cell's entity has a physical tag). The writer omits $Entities for a mesh
// without these arrays, so that reading gives none back.
#include "bisect/check.hpp"
#include "bisect/io.hpp"
#include "bisect/output.hpp"
#include "bisect/text.hpp"
#include "io/file_bytes.hpp"
#include "io/msh_testing.hpp"
#include "io/state_arrays.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace bisect {
namespace {

constexpr std::size_t kNone = std::size_t(-1);
constexpr std::uint32_t kNoIndex = std::numeric_limits<std::uint32_t>::max();
// Whether element references and data tags that run on by one are kept as
// runs (testing::set_msh_element_runs turns it off).
std::atomic<bool> g_element_runs{true};

// ---------------------------------------------------------------------------
// Gmsh element types

struct ElementType {
  int dim = -1; // -1: a type this reader does not know
  int nodes = 0;
  bool simplex = false;
  bool linear = false;
  const char *name = "";
};

// The Gmsh element types that occur in practice (GmshDefines.h numbering).
ElementType element_type(long long type) {
  switch (type) {
  case 1:
    return {1, 2, true, true, "2-node line"};
  case 2:
    return {2, 3, true, true, "3-node triangle"};
  case 3:
    return {2, 4, false, true, "4-node quadrangle"};
  case 4:
    return {3, 4, true, true, "4-node tetrahedron"};
  case 5:
    return {3, 8, false, true, "8-node hexahedron"};
  case 6:
    return {3, 6, false, true, "6-node prism"};
  case 7:
    return {3, 5, false, true, "5-node pyramid"};
  case 8:
    return {1, 3, true, false, "3-node line"};
  case 9:
    return {2, 6, true, false, "6-node triangle"};
  case 10:
    return {2, 9, false, false, "9-node quadrangle"};
  case 11:
    return {3, 10, true, false, "10-node tetrahedron"};
  case 12:
    return {3, 27, false, false, "27-node hexahedron"};
  case 13:
    return {3, 18, false, false, "18-node prism"};
  case 14:
    return {3, 14, false, false, "14-node pyramid"};
  case 15:
    return {0, 1, true, true, "point"};
  case 16:
    return {2, 8, false, false, "8-node quadrangle"};
  case 17:
    return {3, 20, false, false, "20-node hexahedron"};
  case 18:
    return {3, 15, false, false, "15-node prism"};
  case 19:
    return {3, 13, false, false, "13-node pyramid"};
  case 20:
    return {2, 9, true, false, "9-node triangle"};
  case 21:
    return {2, 10, true, false, "10-node triangle"};
  case 22:
    return {2, 12, true, false, "12-node triangle"};
  case 23:
    return {2, 15, true, false, "15-node triangle"};
  case 24:
    return {2, 15, true, false, "15-node incomplete triangle"};
  case 25:
    return {2, 21, true, false, "21-node triangle"};
  case 26:
    return {1, 4, true, false, "4-node line"};
  case 27:
    return {1, 5, true, false, "5-node line"};
  case 28:
    return {1, 6, true, false, "6-node line"};
  case 29:
    return {3, 20, true, false, "20-node tetrahedron"};
  case 30:
    return {3, 35, true, false, "35-node tetrahedron"};
  case 31:
    return {3, 56, true, false, "56-node tetrahedron"};
  case 92:
    return {3, 64, false, false, "64-node hexahedron"};
  case 93:
    return {3, 125, false, false, "125-node hexahedron"};
  default:
    return {};
  }
}

constexpr int kPoint = 15;
constexpr int kLine = 1;
constexpr int kTriangle = 2;
constexpr int kTetrahedron = 4;
// The linear simplex type of each dimension.
constexpr int kSimplexType[4] = {kPoint, kLine, kTriangle, kTetrahedron};

std::string type_text(long long type) {
  return "element type " + std::to_string(type) + " (" + element_type(type).name + ")";
}

// ---------------------------------------------------------------------------
// The file in memory and a cursor over it

// Shows a token in an error message: at most 40 characters, bytes outside
// printable ASCII as \xNN.
std::string quoted(std::string_view t) {
  return "'" + shown_name(t.substr(0, 40)) + (t.size() > 40 ? "...'" : "'");
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

class Source {
public:
  explicit Source(const std::string &path)
      : path_(path), file_(std::make_unique<FileBytes>(path)), text_(file_->view()),
        file_size_(text_.size()) {}

  // Frees the file's bytes once everything is parsed, in binary files (whose
  // messages name byte offsets, not lines): assembling the mesh then does
  // not hold the whole file as well.
  void drop_binary_text() {
    if (!binary)
      return;
    text_ = {};
    pos_ = 0;
    file_.reset();
  }

  bool binary = false; // decided by $MeshFormat
  bool swap = false;   // binary data in the other byte order
  int size_width = 8;  // bytes of a size_t field in 4.1 binary files

  const std::string &path() const { return path_; }
  std::size_t pos() const { return pos_; }
  std::size_t size() const { return text_.size(); }
  std::size_t remaining() const { return text_.size() - pos_; }
  std::size_t at(std::string_view token) const { return std::size_t(token.data() - text_.data()); }

  // Where the next item starts: past blanks in ASCII files (so that errors
  // name its line), exactly here in binary ones.
  std::size_t mark() {
    if (!binary)
      skip_space();
    return pos_;
  }

  // "line N" (ASCII files) or "byte offset N" (binary files).
  std::string where(std::size_t at) const {
    at = std::min(at, file_size_);
    if (binary)
      return "byte offset " + std::to_string(at);
    const auto newlines = std::count(text_.begin(), text_.begin() + std::ptrdiff_t(at), '\n');
    return "line " + std::to_string(newlines + 1);
  }

  [[noreturn]] void fail(std::size_t at, const std::string &what) const {
    throw InputError(path_, where(at) + ": " + what);
  }

  // How many of `n` items of at least `bytes_each` bytes the rest of the file
  // can hold: the most a count read from the file may reserve. (A count too
  // large is then reported where the data runs out.)
  std::size_t affordable(std::uint64_t n, std::uint64_t bytes_each) const {
    return std::size_t(
        std::min<std::uint64_t>(n, remaining() / std::max<std::uint64_t>(bytes_each, 1)));
  }

  // --- text

  void skip_space() {
    while (pos_ < text_.size() && is_space(text_[pos_]))
      ++pos_;
  }
  bool at_end() {
    skip_space();
    return pos_ >= text_.size();
  }

  // The next whitespace-delimited token; fails at the end of the file.
  std::string_view token(std::string_view expected) {
    skip_space();
    if (pos_ >= text_.size())
      fail(pos_, "file ends where " + std::string(expected) + " was expected");
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_]))
      ++pos_;
    last_ = std::string_view(text_).substr(start, pos_ - start);
    return last_;
  }
  // The last token read, quoted for a message.
  std::string last_token() const { return quoted(last_); }

  std::uint64_t count(std::string_view what) {
    const std::string_view t = token(what);
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size())
      fail(at(t),
           "expected " + std::string(what) + " (a non-negative integer), found " + quoted(t));
    return v;
  }

  long long integer(std::string_view what) {
    const std::string_view t = token(what);
    long long v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || v < INT_MIN || v > INT_MAX)
      fail(at(t), "expected " + std::string(what) + " (an integer), found " + quoted(t));
    return v;
  }

  double real(std::string_view what) {
    const std::string_view t = token(what);
    std::string_view s = t;
    if (!s.empty() && s[0] == '+')
      s.remove_prefix(1);
    double v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty() || s[0] == '+')
      fail(at(t), "expected " + std::string(what) + " (a number), found " + quoted(t));
    return v;
  }

  // The rest of the current line without its end-of-line characters; moves
  // past the newline.
  std::string_view line(std::string_view expected) {
    if (pos_ >= text_.size())
      fail(pos_, "file ends where " + std::string(expected) + " was expected");
    const std::size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n')
      ++pos_;
    std::size_t end = pos_;
    if (pos_ < text_.size())
      ++pos_;
    while (end > start && is_space(text_[end - 1]))
      --end;
    return std::string_view(text_).substr(start, end - start);
  }

  // Moves past the newline ending the current line, which must hold nothing
  // else but blanks. Used where binary data starts on the next line (binary
  // data may itself begin with bytes that look like whitespace).
  void finish_line(std::string_view after) {
    while (pos_ < text_.size() &&
           (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\r'))
      ++pos_;
    if (pos_ >= text_.size())
      fail(pos_, "file ends after " + std::string(after));
    if (text_[pos_] != '\n') {
      const std::size_t start = pos_;
      std::size_t end = start;
      while (end < text_.size() && !is_space(text_[end]))
        ++end;
      fail(pos_, "unexpected " + quoted(std::string_view(text_).substr(start, end - start)) +
                     " after " + std::string(after));
    }
    ++pos_;
  }

  // Reads "$End<name>".
  void expect_end(const std::string &name) {
    const std::string marker = "$End" + name;
    const std::string_view t = token(marker);
    if (t != marker)
      fail(at(t), "expected " + marker + ", found " + quoted(t));
  }

  // Moves past the "$End<name>" that closes an unknown section starting at
  // `section_at`. The marker must start a line.
  void skip_section(const std::string &name, std::size_t section_at) {
    const std::string marker = "$End" + name;
    std::size_t p = pos_;
    while ((p = text_.find(marker, p)) != std::string_view::npos) {
      const bool starts_line = p == pos_ || text_[p - 1] == '\n' || text_[p - 1] == '\r';
      const std::size_t after = p + marker.size();
      const bool ends_word = after == text_.size() || is_space(text_[after]);
      if (starts_line && ends_word) {
        pos_ = after;
        return;
      }
      p = after;
    }
    fail(section_at, "section $" + name + " has no " + marker);
  }

  // --- binary

  template <class T> T raw(std::string_view what) {
    if (remaining() < sizeof(T))
      fail(pos_, "file ends inside binary data (" + std::string(what) + ")");
    unsigned char b[sizeof(T)];
    std::memcpy(b, text_.data() + pos_, sizeof(T));
    if (swap)
      std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }

  // A 4.1 size_t field.
  std::uint64_t raw_size(std::string_view what) {
    return size_width == 8 ? raw<std::uint64_t>(what) : raw<std::uint32_t>(what);
  }

  // A 2.2 int field that must not be negative.
  std::uint64_t raw_count(std::string_view what) {
    const std::size_t p = pos_;
    const std::int32_t v = raw<std::int32_t>(what);
    if (v < 0)
      fail(p, "expected " + std::string(what) + " (a non-negative integer), found " +
                  std::to_string(v));
    return std::uint64_t(v);
  }

private:
  std::string path_;
  std::unique_ptr<FileBytes> file_;
  std::string_view text_;
  std::size_t file_size_;
  std::size_t pos_ = 0;
  std::string_view last_;
};

// ---------------------------------------------------------------------------
// What the sections hold, gathered while reading

struct Nodes {
  bool read = false;
  std::vector<std::uint64_t> tag; // sorted by tag once the section is read
  std::vector<double> xyz;        // 3 per node
  std::vector<std::size_t> at;    // where each node is in the file
  bool dense = false;             // tags are tag[0], tag[0] + 1, ... (the usual case)

  std::size_t size() const { return tag.size(); }
  std::size_t find(std::uint64_t t) const {
    if (dense)
      return t >= tag.front() && t - tag.front() < tag.size() ? std::size_t(t - tag.front())
                                                              : kNone;
    const auto it = std::lower_bound(tag.begin(), tag.end(), t);
    return it != tag.end() && *it == t ? std::size_t(it - tag.begin()) : kNone;
  }
};

// The linear simplices of one dimension, in file order.
struct Simplices {
  std::vector<std::uint32_t> nodes; // dim+1 node indices (into Nodes) each
  std::vector<long long> geom;      // elementary entity tag
  std::vector<long long> phys;      // physical tag (2.2 files only; 4.1: empty)
  std::vector<std::uint64_t> tag;   // element tag (to name it in errors)
  std::size_t size() const { return geom.size(); }
};

struct ElementRef {
  std::uint64_t tag;
  std::size_t at;
  int dim;
  std::uint32_t index; // into Simplices[dim] for kept-candidate types, else kNoIndex
};

// Elements whose tags run on by one, at a fixed stride in a binary file:
// the usual file, kept as one run per stretch of a block instead of an
// ElementRef per element (24 bytes each: 129 MB of fresh memory for a
// 5.4 M-tet file, and a tenth of its reading time).
struct ElementRun {
  std::uint64_t first_tag;
  std::size_t count;
  std::size_t at, stride; // the first element's byte offset, and the next one's distance
  int dim;
  std::uint32_t index; // of the first element, or kNoIndex (as in ElementRef)
  ElementRef ref(std::size_t i) const {
    return {first_tag + i, at + i * stride, dim,
            index == kNoIndex ? kNoIndex : index + std::uint32_t(i)};
  }
};

// The first element of some kind, remembered to report it later.
struct Sighting {
  std::size_t at = kNone;
  long long type = 0;
  void note(std::size_t where, long long t) {
    if (at == kNone) {
      at = where;
      type = t;
    }
  }
};

struct DataBlock {
  bool on_nodes = true;
  std::string name;
  int components = 1;
  long long step = 0;
  std::size_t at = 0;
  // The entity tag of each row: while they run on by one (the usual file)
  // only the first and the count are kept, else all (`tags`).
  std::uint64_t first_tag = 0;
  std::size_t run = 0; // rows so far, while they run on by one
  std::vector<std::uint64_t> tags;
  std::vector<double> values; // `components` per tag
  std::size_t size() const { return tags.empty() ? run : tags.size(); }
  std::uint64_t tag(std::size_t i) const { return tags.empty() ? first_tag + i : tags[i]; }
  void add_tag(std::uint64_t t) {
    if (tags.empty() && (run == 0 || t == first_tag + run) && g_element_runs) {
      if (run == 0)
        first_tag = t;
      ++run;
      return;
    }
    if (tags.empty()) {
      tags.reserve(std::max<std::size_t>(2 * run, 16));
      for (std::size_t i = 0; i < run; ++i)
        tags.push_back(first_tag + i);
    }
    tags.push_back(t);
  }
};

struct MshFile {
  int version = 0; // 22 or 41
  Nodes nodes;
  bool elements_read = false;
  std::size_t elements_at = 0;
  Simplices simplices[4];
  // The elements, in file order: as runs while their tags run on by one in
  // a binary file (`runs`), else one reference each (`elements`, sorted by
  // tag before use).
  bool in_runs = true;
  std::vector<ElementRun> runs;
  std::vector<ElementRef> elements;
  int top_dim = -1;                              // highest dimension among simplices of any order
  bool tags22[4] = {false, false, false, false}; // a 2.2 linear simplex carried >= 2 tags
  Sighting non_simplex[4];                       // quads, hexahedra, prisms, pyramids per dimension
  Sighting higher_order[4];                      // curved simplices per dimension
  std::size_t off_plane_at = kNone;              // first triangle with a node off z = 0
  std::string off_plane_what;
  bool have_entities = false;
  // (dim, entity) -> its physical tags, in file order, without repeats or 0
  std::map<std::pair<int, long long>, std::vector<long long>> physicals;
  // The first of an entity's physical tags, or 0 (none, or no such entity).
  long long first_physical(int dim, long long entity) const {
    const auto it = physicals.find({dim, entity});
    return it == physicals.end() || it->second.empty() ? 0 : it->second.front();
  }
  std::vector<DataBlock> data;
  std::vector<PhysicalName> physical_names;
};

// ---------------------------------------------------------------------------
// Sections

void read_format(Source &src, MshFile &f) {
  const std::size_t v_at = src.mark();
  const double v = src.real("the MSH version");
  if (v == 2.2)
    f.version = 22;
  else if (v == 4.1)
    f.version = 41;
  else
    src.fail(v_at, "unsupported MSH version " + src.last_token() + " (supported: 2.2 and 4.1)");
  const std::uint64_t type = src.count("the file type (0 ASCII, 1 binary)");
  if (type > 1)
    src.fail(src.pos(),
             "file type " + std::to_string(type) + " is neither 0 (ASCII) nor 1 (binary)");
  const std::size_t size_at = src.mark();
  const std::uint64_t data_size = src.count("the data size");
  if (type == 1) {
    src.binary = true;
    if (f.version == 22 && data_size != 8)
      src.fail(size_at, "binary MSH 2.2 needs data size 8, found " + std::to_string(data_size));
    if (f.version == 41 && data_size != 4 && data_size != 8)
      src.fail(size_at,
               "binary MSH 4.1 needs a size_t of 4 or 8 bytes, found " + std::to_string(data_size));
    src.size_width = int(data_size);
    src.finish_line("the data size");
    const std::size_t one_at = src.pos();
    const std::int32_t one = src.raw<std::int32_t>("the endianness check");
    if (one == 0x01000000)
      src.swap = true;
    else if (one != 1)
      src.fail(one_at,
               "expected the binary integer 1 (endianness check), found " + std::to_string(one));
  }
  src.expect_end("MeshFormat");
}

// A size_t field (4.1) in an ASCII or binary file.
std::uint64_t size41(Source &src, std::string_view what) {
  return src.binary ? src.raw_size(what) : src.count(what);
}

// An int field in an ASCII or binary file.
long long int41(Source &src, std::string_view what) {
  return src.binary ? src.raw<std::int32_t>(what) : src.integer(what);
}

double real41(Source &src, std::string_view what) {
  return src.binary ? src.raw<double>(what) : src.real(what);
}

// Reads one node of a 2.2 file. A $ParametricNodes node continues with
// the dimension and tag of its entity and its 0, 1 or 2 parametric
// coordinates (u for curves, u v for surfaces).
void read_node22(Source &src, Nodes &n, bool parametric) {
  const std::size_t at = src.mark();
  std::uint64_t tag;
  double xyz[3];
  if (src.binary) {
    tag = src.raw_count("node tag");
    for (double &x : xyz)
      x = src.raw<double>("node coordinate");
  } else {
    tag = src.count("node tag");
    for (double &x : xyz)
      x = src.real("node coordinate");
  }
  if (parametric) {
    const std::size_t dim_at = src.mark();
    const long long dim = int41(src, "node entity dimension");
    if (dim < 0 || dim > 3)
      src.fail(dim_at, "node entity dimension " + std::to_string(dim) + " is not 0..3");
    int41(src, "node entity tag");
    for (long long k = 0; k < (dim == 1 || dim == 2 ? dim : 0); ++k)
      real41(src, "parametric coordinate");
  }
  n.tag.push_back(tag);
  n.at.push_back(at);
  n.xyz.insert(n.xyz.end(), xyz, xyz + 3);
}

// Sorts the nodes by tag and rejects duplicates and non-finite coordinates.
void finish_nodes(Source &src, Nodes &n) {
  for (std::size_t i = 0; i < n.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(n.xyz[3 * i + k]))
        src.fail(n.at[i], "node " + std::to_string(n.tag[i]) + " has a non-finite coordinate");
  if (n.size() >= kNoIndex)
    src.fail(n.at.back(), "too many nodes (more than 2^32 - 1)");
  if (!std::is_sorted(n.tag.begin(), n.tag.end())) {
    std::vector<std::size_t> order(n.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return n.tag[a] < n.tag[b]; });
    Nodes s;
    s.tag.reserve(n.size());
    s.at.reserve(n.size());
    s.xyz.reserve(n.xyz.size());
    for (std::size_t i : order) {
      s.tag.push_back(n.tag[i]);
      s.at.push_back(n.at[i]);
      s.xyz.insert(s.xyz.end(), n.xyz.begin() + std::ptrdiff_t(3 * i),
                   n.xyz.begin() + std::ptrdiff_t(3 * i + 3));
    }
    n.tag = std::move(s.tag);
    n.at = std::move(s.at);
    n.xyz = std::move(s.xyz);
  }
  for (std::size_t i = 1; i < n.size(); ++i)
    if (n.tag[i] == n.tag[i - 1]) {
      const std::size_t later = std::max(n.at[i], n.at[i - 1]);
      const std::size_t first = std::min(n.at[i], n.at[i - 1]);
      src.fail(later, "duplicate node tag " + std::to_string(n.tag[i]) + " (first defined at " +
                          src.where(first) + ")");
    }
  n.dense = !n.tag.empty() && n.tag.back() - n.tag.front() == n.tag.size() - 1;
  n.read = true;
}

void read_nodes22(Source &src, MshFile &f, bool parametric) {
  const std::uint64_t count = src.count("the number of nodes");
  if (src.binary)
    src.finish_line("the number of nodes");
  const std::size_t fits = src.affordable(count, src.binary ? 4 + 3 * 8 : 8);
  f.nodes.tag.reserve(fits);
  f.nodes.at.reserve(fits);
  f.nodes.xyz.reserve(3 * fits);
  for (std::uint64_t i = 0; i < count; ++i)
    read_node22(src, f.nodes, parametric);
  src.expect_end(parametric ? "ParametricNodes" : "Nodes");
  finish_nodes(src, f.nodes);
}

void read_nodes41(Source &src, MshFile &f) {
  const std::size_t sw = std::size_t(src.size_width);
  const std::size_t header_at = src.mark();
  const std::uint64_t blocks = size41(src, "the number of node blocks");
  const std::uint64_t total = size41(src, "the number of nodes");
  size41(src, "the minimum node tag");
  size41(src, "the maximum node tag");
  const std::size_t fits = src.affordable(total, src.binary ? sw + 24 : 8);
  Nodes &n = f.nodes;
  n.tag.reserve(fits);
  n.at.reserve(fits);
  n.xyz.reserve(3 * fits);
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::size_t block_at = src.mark();
    const long long dim = int41(src, "the entity dimension of a node block");
    int41(src, "the entity tag of a node block");
    const long long parametric = int41(src, "the parametric flag of a node block");
    const std::uint64_t count = size41(src, "the number of nodes in a block");
    if (dim < 0 || dim > 3)
      src.fail(block_at, "node block entity dimension " + std::to_string(dim) + " is not 0..3");
    if (parametric != 0 && parametric != 1)
      src.fail(block_at,
               "node block parametric flag " + std::to_string(parametric) + " is not 0 or 1");
    if (count > total - n.size())
      src.fail(block_at,
               "node blocks hold more nodes than the " + std::to_string(total) + " announced");
    const int extra = parametric ? int(dim) : 0; // u, v, w of parametric nodes
    for (std::uint64_t i = 0; i < count; ++i) {
      n.at.push_back(src.mark());
      n.tag.push_back(size41(src, "node tag"));
    }
    for (std::uint64_t i = 0; i < count; ++i) {
      for (int k = 0; k < 3; ++k)
        n.xyz.push_back(real41(src, "node coordinate"));
      for (int k = 0; k < extra; ++k)
        real41(src, "parametric node coordinate");
    }
  }
  if (n.size() != total)
    src.fail(header_at, "node header announces " + std::to_string(total) +
                            " nodes, the blocks hold " + std::to_string(n.size()));
  src.expect_end("Nodes");
  finish_nodes(src, n);
}

// Records one element: its tag (for duplicate checks and element data), its
// nodes if it may become a cell, and what kind of element it is.
// Records an element's reference: as part of a run while the tags run on
// by one (stride: the distance to the next element in a binary block, 0 in
// ASCII files), else in f.elements, the runs so far first.
void note_element(MshFile &f, const ElementRef &ref, std::size_t stride) {
  if (f.in_runs) {
    if (!g_element_runs)
      stride = 0; // a test's choice: one reference per element
    if (stride != 0 &&
        (f.runs.empty() || ref.tag == f.runs.back().first_tag + f.runs.back().count)) {
      if (!f.runs.empty()) {
        ElementRun &r = f.runs.back();
        const bool indexed = r.index != kNoIndex;
        if (r.dim == ref.dim && r.stride == stride && r.at + r.count * stride == ref.at &&
            indexed == (ref.index != kNoIndex) &&
            (!indexed || r.index + r.count == std::size_t(ref.index))) {
          ++r.count;
          return;
        }
      }
      f.runs.push_back({ref.tag, 1, ref.at, stride, ref.dim, ref.index});
      return;
    }
    f.in_runs = false;
    for (const ElementRun &r : f.runs)
      for (std::size_t i = 0; i < r.count; ++i)
        f.elements.push_back(r.ref(i));
    f.runs = {};
  }
  f.elements.push_back(ref);
}

void add_element(Source &src, MshFile &f, std::uint64_t tag, long long type, const ElementType &et,
                 long long geom, long long phys, const std::uint64_t *node_tags, std::size_t at,
                 std::size_t stride) {
  std::uint32_t idx[4] = {0, 0, 0, 0};
  for (int k = 0; k < et.nodes; ++k) {
    const std::size_t p = f.nodes.find(node_tags[k]);
    if (p == kNone)
      src.fail(at, "element " + std::to_string(tag) + " refers to node " +
                       std::to_string(node_tags[k]) + ", which is not in $Nodes");
    if (k < 4)
      idx[k] = std::uint32_t(p);
  }
  ElementRef ref{tag, at, et.dim, kNoIndex};
  if (et.simplex && et.dim >= 2)
    f.top_dim = std::max(f.top_dim, et.dim);
  if (type == kTriangle || type == kTetrahedron || type == kLine || type == kPoint) {
    // Cells, or (below the cell dimension) tagged entities.
    Simplices &s = f.simplices[et.dim];
    if (s.size() >= kNoIndex - 1)
      src.fail(at, "too many cells (more than 2^32 - 2)");
    ref.index = std::uint32_t(s.size());
    s.nodes.insert(s.nodes.end(), idx, idx + et.nodes);
    s.geom.push_back(geom);
    if (f.version == 22) // 4.1 files have their physical tags by entity
      s.phys.push_back(phys);
    s.tag.push_back(tag);
    if (type == kTriangle && f.off_plane_at == kNone)
      for (int k = 0; k < 3; ++k) {
        const double z = f.nodes.xyz[3 * std::size_t(idx[k]) + 2];
        if (z != 0) {
          f.off_plane_at = at;
          char buf[64];
          std::snprintf(buf, sizeof buf, "%.17g", z);
          f.off_plane_what = "triangle " + std::to_string(tag) + " has node " +
                             std::to_string(node_tags[k]) + " at z = " + buf;
          break;
        }
      }
  } else if (et.dim >= 2 && !et.simplex) {
    f.non_simplex[et.dim].note(at, type);
  } else if (et.dim >= 2 && !et.linear) {
    f.higher_order[et.dim].note(at, type);
  }
  note_element(f, ref, stride);
}

// Room for `count` more elements of a block of type `et` (at most what the
// rest of the file can hold, `bytes_each` per element at least): one
// allocation per large block instead of a doubling copy of every array.
void reserve_block(Source &src, MshFile &f, long long type, const ElementType &et,
                   std::uint64_t count, std::uint64_t bytes_each) {
  if (et.dim < 0 || et.dim > 3 || type != kSimplexType[et.dim])
    return; // not kept by add_element
  Simplices &s = f.simplices[et.dim];
  const std::size_t need = s.size() + src.affordable(count, bytes_each);
  if (need <= s.geom.capacity())
    return;
  const std::size_t room = std::max(need, 2 * s.geom.capacity());
  s.nodes.reserve(room * std::size_t(et.nodes));
  s.geom.reserve(room);
  if (f.version == 22)
    s.phys.reserve(room);
  s.tag.reserve(room);
}

// The element type at `at`, which must be one this reader knows.
ElementType known_type(Source &src, long long type, std::size_t at) {
  const ElementType et = element_type(type);
  if (et.dim < 0)
    src.fail(at, "unknown or unsupported element type " + std::to_string(type));
  return et;
}

void require_nodes_before_elements(Source &src, const MshFile &f, std::size_t at) {
  if (!f.nodes.read)
    src.fail(at, "$Elements comes before $Nodes");
  if (f.elements_read)
    src.fail(at, "second $Elements section");
}

void read_elements22(Source &src, MshFile &f) {
  const std::uint64_t total = src.count("the number of elements");
  f.elements.reserve(src.affordable(total, 8));
  std::vector<std::uint64_t> node_tags;
  auto note_tags = [&](const ElementType &et, std::uint64_t ntags, long long) {
    if (ntags >= 2 && et.simplex && et.linear)
      f.tags22[et.dim] = true;
  };
  if (src.binary) {
    src.finish_line("the number of elements");
    std::uint64_t done = 0;
    while (done < total) {
      const std::size_t block_at = src.pos();
      const long long type = src.raw<std::int32_t>("element type");
      const std::uint64_t count = src.raw_count("the number of elements in a block");
      const std::uint64_t ntags = src.raw_count("the number of element tags");
      const ElementType et = known_type(src, type, block_at);
      if (count == 0 || count > total - done)
        src.fail(block_at, "element block of " + std::to_string(count) +
                               " elements does not fit the " + std::to_string(total - done) +
                               " elements left of the " + std::to_string(total) + " announced");
      node_tags.resize(std::size_t(et.nodes));
      reserve_block(src, f, type, et, count, 4 * (1 + ntags + std::uint64_t(et.nodes)));
      for (std::uint64_t i = 0; i < count; ++i) {
        const std::size_t at = src.pos();
        const std::uint64_t tag = src.raw_count("element tag");
        long long tags[2] = {0, 0};
        for (std::uint64_t j = 0; j < ntags; ++j) {
          const long long v = src.raw<std::int32_t>("element tag");
          if (j < 2)
            tags[j] = v;
        }
        for (std::uint64_t &n : node_tags)
          n = src.raw_count("node tag");
        note_tags(et, ntags, type);
        add_element(src, f, tag, type, et, tags[1], tags[0], node_tags.data(), at,
                    4 * std::size_t(1 + ntags + std::uint64_t(et.nodes)));
      }
      done += count;
    }
  } else {
    for (std::uint64_t i = 0; i < total; ++i) {
      const std::size_t at = src.mark();
      const std::uint64_t tag = src.count("element tag");
      const std::size_t type_at = src.mark();
      const long long type = src.integer("element type");
      const ElementType et = known_type(src, type, type_at);
      const std::uint64_t ntags = src.count("the number of element tags");
      long long tags[2] = {0, 0};
      for (std::uint64_t j = 0; j < ntags; ++j) {
        const long long v = src.integer("element tag");
        if (j < 2)
          tags[j] = v;
      }
      node_tags.resize(std::size_t(et.nodes));
      for (std::uint64_t &n : node_tags)
        n = src.count("node tag");
      note_tags(et, ntags, type);
      add_element(src, f, tag, type, et, tags[1], tags[0], node_tags.data(), at, 0);
    }
  }
  src.expect_end("Elements");
}

void read_elements41(Source &src, MshFile &f) {
  const std::size_t sw = std::size_t(src.size_width);
  const std::size_t header_at = src.mark();
  const std::uint64_t blocks = size41(src, "the number of element blocks");
  const std::uint64_t total = size41(src, "the number of elements");
  size41(src, "the minimum element tag");
  size41(src, "the maximum element tag");
  f.elements.reserve(src.affordable(total, src.binary ? 2 * sw : 4));
  std::vector<std::uint64_t> node_tags;
  std::uint64_t done = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::size_t block_at = src.mark();
    const long long dim = int41(src, "the entity dimension of an element block");
    const long long entity = int41(src, "the entity tag of an element block");
    const long long type = int41(src, "the element type of an element block");
    const std::uint64_t count = size41(src, "the number of elements in a block");
    const ElementType et = known_type(src, type, block_at);
    if (dim != et.dim)
      src.fail(block_at,
               "element block of dimension " + std::to_string(dim) + " holds " + type_text(type));
    if (count > total - done)
      src.fail(block_at, "element blocks hold more elements than the " + std::to_string(total) +
                             " announced");
    node_tags.resize(std::size_t(et.nodes));
    reserve_block(src, f, type, et, count, src.binary ? sw * std::uint64_t(1 + et.nodes) : 4);
    for (std::uint64_t i = 0; i < count; ++i) {
      const std::size_t at = src.mark();
      const std::uint64_t tag = size41(src, "element tag");
      for (std::uint64_t &n : node_tags)
        n = size41(src, "node tag");
      add_element(src, f, tag, type, et, entity, 0, node_tags.data(), at,
                  src.binary ? sw * std::size_t(1 + et.nodes) : 0);
    }
    done += count;
  }
  if (done != total)
    src.fail(header_at, "element header announces " + std::to_string(total) +
                            " elements, the blocks hold " + std::to_string(done));
  src.expect_end("Elements");
}

// 4.1 $Entities: remembers the physical tags of every entity (an entity in
// several physical groups lists them all), at most kMaxGroupsPerEntity.
constexpr std::size_t kMaxGroupsPerEntity = 64;
void read_entities41(Source &src, MshFile &f) {
  std::uint64_t counts[4];
  for (std::uint64_t &c : counts)
    c = size41(src, "the number of entities");
  for (int d = 0; d < 4; ++d) {
    for (std::uint64_t i = 0; i < counts[d]; ++i) {
      const std::size_t at = src.mark();
      const long long tag = int41(src, "entity tag");
      for (int k = 0; k < (d == 0 ? 3 : 6); ++k)
        real41(src, "entity bounding box coordinate");
      const std::uint64_t nphys = size41(src, "the number of physical tags");
      std::vector<long long> tags;
      for (std::uint64_t j = 0; j < nphys; ++j) {
        const long long p = int41(src, "physical tag");
        if (p == 0 || std::find(tags.begin(), tags.end(), p) != tags.end())
          continue;
        // The entity's elements are kept once per group (add_entities): a
        // bound on the groups bounds what a small file can make us hold.
        if (tags.size() == kMaxGroupsPerEntity)
          src.fail(at, "entity (dimension " + std::to_string(d) + ", tag " + std::to_string(tag) +
                           ") is in more than " + std::to_string(kMaxGroupsPerEntity) +
                           " physical groups");
        tags.push_back(p);
      }
      if (d > 0) {
        const std::uint64_t nb = size41(src, "the number of bounding entities");
        for (std::uint64_t j = 0; j < nb; ++j)
          int41(src, "bounding entity tag");
      }
      if (!f.physicals.emplace(std::make_pair(d, tag), std::move(tags)).second)
        src.fail(at, "duplicate entity (dimension " + std::to_string(d) + ", tag " +
                         std::to_string(tag) + ")");
    }
  }
  src.expect_end("Entities");
  f.have_entities = true;
}

// Adds a data section to the ones read: a later section of the same name
// replaces an earlier one (a later time step) unless it continues the same
// time step (a partitioned file), in which case the entries are appended.
void keep_data(Source &src, MshFile &f, DataBlock &&b) {
  for (DataBlock &d : f.data) {
    if (d.on_nodes != b.on_nodes || d.name != b.name)
      continue;
    if (d.step != b.step) {
      d = std::move(b);
    } else {
      if (d.components != b.components)
        src.fail(b.at, "data " + quoted(b.name) + " changes from " + std::to_string(d.components) +
                           " to " + std::to_string(b.components) +
                           " components within one time step");
      for (std::size_t i = 0; i < b.size(); ++i)
        d.add_tag(b.tag(i));
      d.values.insert(d.values.end(), b.values.begin(), b.values.end());
    }
    return;
  }
  f.data.push_back(std::move(b));
}

// $NodeData / $ElementData (same layout in 2.2 and 4.1).
void read_data(Source &src, MshFile &f, bool on_nodes, std::size_t section_at) {
  const std::string section = on_nodes ? "NodeData" : "ElementData";
  DataBlock b;
  b.on_nodes = on_nodes;
  b.at = section_at;
  const std::size_t nstr_at = src.mark();
  const std::uint64_t nstr = src.count("the number of string tags");
  if (nstr == 0)
    src.fail(nstr_at, "$" + section + " without a name (no string tags)");
  src.finish_line("the number of string tags");
  for (std::uint64_t i = 0; i < nstr; ++i) {
    std::string_view s = src.line("a string tag");
    while (!s.empty() && is_space(s.front()))
      s.remove_prefix(1);
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"')
      s = s.substr(1, s.size() - 2);
    if (i == 0)
      b.name = std::string(s);
  }
  const std::uint64_t nreal = src.count("the number of real tags");
  for (std::uint64_t i = 0; i < nreal; ++i)
    src.real("real tag");
  const std::size_t nint_at = src.mark();
  const std::uint64_t nint = src.count("the number of integer tags");
  if (nint < 3)
    src.fail(nint_at, "expected at least 3 integer tags (time step, components, entries), found " +
                          std::to_string(nint));
  b.step = src.integer("the time step");
  const std::size_t comp_at = src.mark();
  const std::uint64_t components = src.count("the number of components");
  if (components < 1 || components > 4096)
    src.fail(comp_at, "number of components " + std::to_string(components) + " is not in 1..4096");
  b.components = int(components);
  const std::uint64_t n = src.count("the number of entries");
  for (std::uint64_t i = 3; i < nint; ++i)
    src.integer("integer tag");
  if (src.binary)
    src.finish_line("the integer tags");
  const std::size_t fits =
      src.affordable(n, src.binary ? 4 + 8 * components : 2 * (1 + components));

  b.values.reserve(fits * components);
  for (std::uint64_t i = 0; i < n; ++i) {
    b.add_tag(src.binary ? src.raw_count("data entity tag") : src.count("data entity tag"));
    for (std::uint64_t k = 0; k < components; ++k)
      b.values.push_back(src.binary ? src.raw<double>("data value") : src.real("data value"));
  }
  src.expect_end(section);
  keep_data(src, f, std::move(b));
}

// $PhysicalNames (text in binary files too): count, then "dim tag "name""
// per line. Names keep their spaces; the quotes go.
void read_physical_names(Source &src, MshFile &f) {
  const std::uint64_t n = src.count("the number of physical names");
  for (std::uint64_t i = 0; i < n; ++i) {
    const std::size_t at = src.mark();
    const long long dim = src.integer("a physical name's dimension");
    if (dim < 0 || dim > 3)
      src.fail(at, "physical name dimension " + std::to_string(dim) + " is not 0..3");
    const long long tag = src.integer("a physical tag");
    src.skip_space();
    std::string_view name = src.line("a physical name");
    while (!name.empty() && (name.back() == '\r' || name.back() == ' ' || name.back() == '\t'))
      name.remove_suffix(1);
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"')
      name = name.substr(1, name.size() - 2);
    // A name is written back between quotes on one line (and into .vtu
    // field data): a quote or a control character in it is a broken file.
    if (std::find_if(name.begin(), name.end(), [](char c) {
          return c == '"' || static_cast<unsigned char>(c) < 0x20;
        }) != name.end())
      src.fail(at,
               "physical name " + quoted(name) + " contains a double quote or a control character");
    f.physical_names.push_back({int(dim), int(tag), std::string(name)});
  }
  src.expect_end("PhysicalNames");
}

MshFile parse(Source &src) {
  MshFile f;
  const std::string_view first = src.token("$MeshFormat");
  if (first == "$NOD" || first == "$NOE")
    src.fail(src.at(first), "MSH version 1 files are not supported (supported: 2.2 and 4.1)");
  if (first != "$MeshFormat")
    src.fail(src.at(first),
             "expected $MeshFormat at the start of a .msh file, found " + quoted(first));
  read_format(src, f);
  while (!src.at_end()) {
    const std::string_view t = src.token("a section header");
    const std::size_t at = src.at(t);
    if (t.size() < 2 || t[0] != '$')
      src.fail(at, "expected a section header such as $Nodes, found " + quoted(t));
    const std::string name(t.substr(1));
    if (name.rfind("End", 0) == 0)
      src.fail(at, "unexpected " + quoted(t) + " outside its section");
    src.finish_line("$" + name);
    if (name == "Nodes" || (name == "ParametricNodes" && f.version == 22)) {
      if (f.nodes.read)
        src.fail(at, "second $Nodes section");
      f.version == 22 ? read_nodes22(src, f, name == "ParametricNodes") : read_nodes41(src, f);
    } else if (name == "Elements") {
      require_nodes_before_elements(src, f, at);
      f.elements_at = at;
      f.version == 22 ? read_elements22(src, f) : read_elements41(src, f);
      f.elements_read = true;
    } else if (name == "Entities" && f.version == 41) {
      if (f.have_entities)
        src.fail(at, "second $Entities section");
      read_entities41(src, f);
    } else if (name == "NodeData" || name == "ElementData") {
      read_data(src, f, name == "NodeData", at);
    } else if (name == "PhysicalNames") {
      read_physical_names(src, f);
    } else {
      src.skip_section(name, at); // $Periodic, $Comments, ...
    }
  }
  if (!f.nodes.read)
    src.fail(src.size(), "no $Nodes section");
  if (!f.elements_read)
    src.fail(src.size(), "no $Elements section");
  return f;
}

// ---------------------------------------------------------------------------
// From the sections to the Mesh

void reject_duplicate_elements(Source &src, MshFile &f) {
  if (f.in_runs)
    return; // tags that run on by one: sorted, none twice
  const auto by_tag = [](const ElementRef &a, const ElementRef &b) {
    return a.tag != b.tag ? a.tag < b.tag : a.at < b.at;
  };
  if (!std::is_sorted(f.elements.begin(), f.elements.end(), by_tag))
    std::sort(f.elements.begin(), f.elements.end(), by_tag);
  for (std::size_t i = 1; i < f.elements.size(); ++i)
    if (f.elements[i].tag == f.elements[i - 1].tag)
      src.fail(f.elements[i].at, "duplicate element tag " + std::to_string(f.elements[i].tag) +
                                     " (first defined at " + src.where(f.elements[i - 1].at) + ")");
}

// The cell dimension, after rejecting what this reader does not handle.
int cell_dimension(Source &src, const MshFile &f) {
  const int dim = f.top_dim;
  if (dim < 2)
    src.fail(f.elements_at, "no triangles or tetrahedra in $Elements");
  const char *cells = dim == 3 ? "tetrahedra" : "triangles";
  if (f.higher_order[dim].at != kNone)
    src.fail(f.higher_order[dim].at,
             type_text(f.higher_order[dim].type) +
                 ": higher-order simplices are not supported (only linear " + cells + ")");
  if (f.non_simplex[dim].at != kNone)
    src.fail(f.non_simplex[dim].at,
             "mixed non-simplex cells: " + type_text(f.non_simplex[dim].type) + " among the " +
                 cells + " is not supported");
  if (dim == 2 && f.non_simplex[3].at != kNone) // volume cells beside a triangle mesh
    src.fail(f.non_simplex[3].at, "mixed non-simplex cells: " + type_text(f.non_simplex[3].type) +
                                      " in a triangle mesh is not supported");
  return dim; // triangles off z = 0: see settle_plane in io.cpp
}

// "gmsh:physical" and "gmsh:geometrical", when the file provides them.
void add_gmsh_tags(const MshFile &f, int dim, Mesh &m) {
  const Simplices &s = f.simplices[dim];
  DataArray phys{"gmsh:physical", 1, {}}, geom{"gmsh:geometrical", 1, {}};
  bool any_phys = false;
  if (f.version == 22) {
    if (!f.tags22[dim])
      return;
    phys.values.assign(s.phys.begin(), s.phys.end());
    any_phys = true;
  } else {
    if (!f.have_entities)
      return;
    phys.values.reserve(s.size());
    // Cells come in blocks of one entity: the map is asked once a run.
    long long last_geom = 0, p = 0;
    for (std::size_t c = 0; c < s.size(); ++c) {
      if (c == 0 || s.geom[c] != last_geom) {
        last_geom = s.geom[c];
        p = f.first_physical(dim, last_geom);
      }
      any_phys |= p != 0;
      phys.values.push_back(double(p));
    }
  }
  geom.values.assign(s.geom.begin(), s.geom.end());
  if (any_phys)
    m.cell_data.push_back(std::move(phys));
  m.cell_data.push_back(std::move(geom));
}

DataArray node_array(Source &src, const MshFile &f, const DataBlock &b,
                     const std::vector<VertexId> &vertex_of, std::size_t nv) {
  const std::size_t nc = std::size_t(b.components);
  DataArray a{b.name, b.components, std::vector<double>(nv * nc, 0.0)};
  std::vector<char> covered(nv, 0);
  for (std::size_t i = 0; i < b.size(); ++i) {
    const std::size_t p = f.nodes.find(b.tag(i));
    if (p == kNone)
      src.fail(b.at, "node data " + quoted(b.name) + " refers to node " + std::to_string(b.tag(i)) +
                         ", which is not in $Nodes");
    const VertexId v = vertex_of[p];
    if (v == kNoVertex)
      continue;
    std::copy_n(b.values.begin() + std::ptrdiff_t(i * nc), nc,
                a.values.begin() + std::ptrdiff_t(v * nc));
    covered[v] = 1;
  }
  for (std::size_t p = 0; p < vertex_of.size(); ++p)
    if (vertex_of[p] != kNoVertex && !covered[vertex_of[p]])
      src.fail(b.at, "node data " + quoted(b.name) + " has no value for node " +
                         std::to_string(f.nodes.tag[p]));
  return a;
}

// Every element in tag order (after reject_duplicate_elements).
template <class Visit> void for_each_element(const MshFile &f, Visit &&visit) {
  if (!f.in_runs) {
    for (const ElementRef &e : f.elements)
      visit(e);
    return;
  }
  for (const ElementRun &r : f.runs)
    for (std::size_t i = 0; i < r.count; ++i)
      visit(r.ref(i));
}

// Finds elements by tag (after reject_duplicate_elements). Data usually
// lists the elements in tag order: the element after the last one found is
// tried before a binary search.
class ElementFinder {
public:
  explicit ElementFinder(const MshFile &f) : f_(f) {}
  bool find(std::uint64_t tag, ElementRef &out) {
    if (!f_.in_runs) {
      const auto &e = f_.elements;
      const auto it =
          next_ < e.size() && e[next_].tag == tag
              ? e.begin() + std::ptrdiff_t(next_)
              : std::lower_bound(e.begin(), e.end(), tag,
                                 [](const ElementRef &r, std::uint64_t t) { return r.tag < t; });
      if (it != e.end())
        next_ = std::size_t(it - e.begin()) + 1;
      if (it == e.end() || it->tag != tag)
        return false;
      out = *it;
      return true;
    }
    // Runs: one range of tags, each run starting where the last one ends.
    const auto &r = f_.runs;
    if (r.empty() || tag < r.front().first_tag ||
        tag - r.front().first_tag >= r.back().first_tag + r.back().count - r.front().first_tag)
      return false;
    if (!(next_ < r.size() && tag >= r[next_].first_tag &&
          tag - r[next_].first_tag < r[next_].count))
      next_ = std::size_t(std::upper_bound(r.begin(), r.end(), tag,
                                           [](std::uint64_t t, const ElementRun &x) {
                                             return t < x.first_tag;
                                           }) -
                          r.begin()) -
              1;
    out = r[next_].ref(std::size_t(tag - r[next_].first_tag));
    return true;
  }

private:
  const MshFile &f_;
  std::size_t next_ = 0;
};

DataArray cell_array(Source &src, const MshFile &f, DataBlock &b, int dim) {
  const std::size_t nc = std::size_t(b.components);
  const std::size_t ncells = f.simplices[dim].size();
  // The usual file: row i holds cell i's values, every cell once. The rows
  // are then the array as they are (5.4 M tets: 48 MB of fresh memory and
  // a copy less per array).
  if (b.size() == ncells) {
    ElementFinder finder(f);
    ElementRef e;
    bool in_order = true;
    for (std::size_t i = 0; i < ncells && in_order; ++i)
      in_order = finder.find(b.tag(i), e) && e.dim == dim && e.index == i;
    if (in_order)
      return DataArray{b.name, b.components, std::move(b.values)};
  }
  DataArray a{b.name, b.components, std::vector<double>(ncells * nc, 0.0)};
  std::vector<char> covered(ncells, 0);
  ElementFinder finder(f);
  ElementRef e;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (!finder.find(b.tag(i), e))
      src.fail(b.at, "element data " + quoted(b.name) + " refers to element " +
                         std::to_string(b.tag(i)) + ", which is not in $Elements");
    if (e.dim != dim || e.index == kNoIndex)
      continue; // a dropped lower-dimensional element
    std::copy_n(b.values.begin() + std::ptrdiff_t(i * nc), nc,
                a.values.begin() + std::ptrdiff_t(e.index * nc));
    covered[e.index] = 1;
  }
  bool complete = true;
  for_each_element(f, [&](const ElementRef &r) {
    if (complete && r.dim == dim && r.index != kNoIndex && !covered[r.index]) {
      complete = false;
      e = r;
    }
  });
  if (!complete)
    src.fail(b.at, "element data " + quoted(b.name) + " has no value for element " +
                       std::to_string(e.tag));
  return a;
}

// The elements of dimension below the mesh's that belong to a physical group
// (2.2: physical tag != 0; 4.1: their entity has a physical tag) become
// tagged entities with gmsh:physical and gmsh:geometrical; each must be a
// face of some cell. Elements outside any physical group are Gmsh's mesh of
// the geometry's boundary, which nothing asked to keep: they go.
void add_entities(Source &src, const MshFile &f, const std::vector<VertexId> &vertex_of, Mesh &m) {
  static const char *const kNames[4] = {"point", "line", "triangle", "tetrahedron"};
  for (int d = 0; d < m.dim; ++d) {
    const Simplices &s = f.simplices[d];
    const std::size_t nvs = std::size_t(d + 1);
    Entities block;
    block.dim = d;
    DataArray phys{"gmsh:physical", 1, {}, ValueType::Int32};
    DataArray geom{"gmsh:geometrical", 1, {}, ValueType::Int32};
    std::vector<std::size_t> source; // the element of each entity
    auto add = [&](std::size_t e, long long p) {
      for (std::size_t k = 0; k < nvs; ++k)
        block.vertices.push_back(vertex_of[s.nodes[e * nvs + k]]); // kNoVertex: not a face
      phys.values.push_back(double(p));
      geom.values.push_back(double(s.geom[e]));
      source.push_back(e);
    };
    if (f.version == 22) {
      // An element in two groups is in the file twice, once with each tag.
      if (f.tags22[d])
        for (std::size_t e = 0; e < s.size(); ++e)
          if (s.phys[e] != 0)
            add(e, s.phys[e]);
    } else {
      // An entity in several physical groups: its elements once per group,
      // a run of the entity's elements for each tag in turn (as a 2.2 file
      // lists them), so that every group keeps all of its faces.
      static const std::vector<long long> kNone;
      for (std::size_t lo = 0, hi; lo < s.size(); lo = hi) {
        for (hi = lo + 1; hi < s.size() && s.geom[hi] == s.geom[lo];)
          ++hi;
        const auto it = f.physicals.find({d, s.geom[lo]});
        for (long long p : it == f.physicals.end() ? kNone : it->second)
          for (std::size_t e = lo; e < hi; ++e)
            add(e, p);
      }
    }
    if (source.empty())
      continue;
    block.data.push_back(std::move(phys));
    block.data.push_back(std::move(geom));
    const std::size_t bad = first_entity_not_a_face(m, block);
    if (bad != std::size_t(-1)) {
      const std::size_t e = source[bad];
      std::size_t at = f.elements_at;
      if (ElementRef r; ElementFinder(f).find(s.tag[e], r))
        at = r.at;
      src.fail(at, "element " + std::to_string(s.tag[e]) + " (" + kNames[d] + ", physical " +
                       std::to_string((long long)block.data[0].values[bad]) +
                       ") is not a face of the mesh");
    }
    m.entities.push_back(std::move(block));
  }
  m.physical_names = f.physical_names;
}

// Messages about the mesh name Gmsh's node and element tags (mesh.hpp,
// FileNumbering): vertices are the used nodes in tag order, cells the
// elements in tag order (`order`, or file order when empty). Tags that are
// the index plus a constant (the usual file) are kept as that constant.
void number_by_tags(const MshFile &f, const std::vector<VertexId> &vertex_of,
                    const std::vector<std::uint32_t> &order, Mesh &m) {
  FileNumbering &n = m.numbering;
  n.gmsh = true;
  n.vertices = m.num_vertices();
  n.cells = m.num_cells();
  auto settle = [](std::vector<std::uint64_t> &tags, std::uint64_t &base) {
    bool dense = true;
    for (std::size_t i = 1; i < tags.size() && dense; ++i)
      dense = tags[i] == tags[0] + i;
    if (dense) {
      base = tags.empty() ? 1 : tags[0];
      tags = {};
    }
  };
  n.node_tags.reserve(n.vertices);
  for (std::size_t p = 0; p < vertex_of.size(); ++p)
    if (vertex_of[p] != kNoVertex)
      n.node_tags.push_back(f.nodes.tag[p]);
  settle(n.node_tags, n.node_base);
  const Simplices &s = f.simplices[m.dim];
  n.element_tags.reserve(n.cells);
  for (std::size_t i = 0; i < s.size(); ++i)
    n.element_tags.push_back(s.tag[order.empty() ? i : order[i]]);
  settle(n.element_tags, n.element_base);
}

Mesh assemble(Source &src, MshFile &f) {
  reject_duplicate_elements(src, f);
  const int dim = cell_dimension(src, f);
  Simplices &s = f.simplices[dim];
  Mesh m;
  m.dim = dim;
  // Vertices: the nodes the cells use, in increasing tag order.
  std::vector<VertexId> vertex_of(f.nodes.size(), kNoVertex);
  for (std::uint32_t p : s.nodes)
    vertex_of[p] = 0;
  VertexId nv = 0;
  for (std::size_t p = 0; p < vertex_of.size(); ++p)
    if (vertex_of[p] != kNoVertex)
      vertex_of[p] = nv++;
  // Every node used (the usual file): node p is vertex p, and a 3D mesh
  // takes the nodes' coordinates and the cells' node indices as they are,
  // without copying them (on a 5.4 M-tet file 110 MB of fresh memory less).
  const bool every_node = nv == f.nodes.size();
  if (every_node && dim == 3) {
    m.coords = std::move(f.nodes.xyz);
  } else {
    m.coords.reserve(std::size_t(nv) * std::size_t(dim));
    for (std::size_t p = 0; p < vertex_of.size(); ++p)
      if (vertex_of[p] != kNoVertex)
        m.coords.insert(m.coords.end(), f.nodes.xyz.begin() + std::ptrdiff_t(3 * p),
                        f.nodes.xyz.begin() + std::ptrdiff_t(3 * p + std::size_t(dim)));
  }
  if (dim == 2 && f.off_plane_at != kNone) {
    DataArray z{kPlaneZArray, 1, {}};
    z.values.reserve(nv);
    for (std::size_t p = 0; p < vertex_of.size(); ++p)
      if (vertex_of[p] != kNoVertex)
        z.values.push_back(f.nodes.xyz[3 * p + 2]);
    m.point_data.push_back(std::move(z));
  }
  if (every_node) {
    m.cells = std::move(s.nodes);
  } else {
    m.cells.reserve(s.nodes.size());
    for (std::uint32_t p : s.nodes)
      m.cells.push_back(vertex_of[p]);
  }
  add_gmsh_tags(f, dim, m);
  for (DataBlock &b : f.data) {
    if (b.on_nodes)
      m.point_data.push_back(node_array(src, f, b, vertex_of, nv));
    else
      m.cell_data.push_back(cell_array(src, f, b, dim));
    b.tags = {}; // done with: the file's copy need not outlive it
    b.values = {};
  }
  // Cells in element tag order (for_each_element): a file whose
  // blocks group the elements by entity, as Gmsh and our writer make them,
  // gives back the cell order the tags say.
  std::vector<std::uint32_t> by_tag;
  by_tag.reserve(s.size());
  for_each_element(f, [&](const ElementRef &e) {
    if (e.dim == dim && e.index != kNoIndex)
      by_tag.push_back(e.index);
  });
  bool identity = true;
  for (std::size_t i = 0; i < by_tag.size() && identity; ++i)
    identity = by_tag[i] == i;
  if (!identity && by_tag.size() == s.size()) {
    const std::size_t nvc = std::size_t(dim + 1);
    std::vector<VertexId> cells(m.cells.size());
    for (std::size_t i = 0; i < by_tag.size(); ++i)
      std::copy_n(m.cells.begin() + std::ptrdiff_t(by_tag[i] * nvc), nvc,
                  cells.begin() + std::ptrdiff_t(i * nvc));
    m.cells = std::move(cells);
    for (DataArray &a : m.cell_data) {
      const std::size_t k = std::size_t(a.components);
      std::vector<double> values(a.values.size());
      for (std::size_t i = 0; i < by_tag.size(); ++i)
        std::copy_n(a.values.begin() + std::ptrdiff_t(by_tag[i] * k), k,
                    values.begin() + std::ptrdiff_t(i * k));
      a.values = std::move(values);
    }
  }
  add_entities(src, f, vertex_of, m);
  number_by_tags(f, vertex_of, by_tag.size() == s.size() ? by_tag : std::vector<std::uint32_t>(),
                 m);
  return m;
}

// ---------------------------------------------------------------------------
// Writing (MSH 4.1 binary)

// v's bytes at `at`.
template <class T> void store(char *at, T v) {
  std::memcpy(at, &v, sizeof(T));
}

// A buffered binary output file; errors become InputError naming the file.
class Output {
public:
  explicit Output(const std::string &path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
    if (!file_)
      throw InputError(path, "cannot write: " + write_failure(errno));
  }
  ~Output() {
    if (file_)
      std::fclose(file_);
  }
  Output(const Output &) = delete;
  Output &operator=(const Output &) = delete;

  void text(std::string_view s) {
    if (s.size() > kBuffer - used_) {
      flush();
      if (s.size() > kBuffer) {
        put(s.data(), s.size());
        return;
      }
    }
    std::memcpy(buffer_.get() + used_, s.data(), s.size());
    used_ += s.size();
  }
  template <class T> void raw(T v) { std::memcpy(span(sizeof(T)), &v, sizeof(T)); }
  void size(std::uint64_t v) { raw<std::uint64_t>(v); }
  void int32(long long v) { raw<std::int32_t>(std::int32_t(v)); }
  // Room for the next n bytes (n at most kSpan), to be filled by the caller
  // before anything else is written.
  static constexpr std::size_t kSpan = std::size_t(1) << 20;
  char *span(std::size_t n) {
    if (n > kBuffer - used_)
      flush();
    char *at = buffer_.get() + used_;
    used_ += n;
    return at;
  }

  void close() {
    flush();
    const int rc = std::fclose(file_);
    if (rc != 0 && !error_)
      error_ = errno ? errno : EIO;
    file_ = nullptr;
    if (error_)
      throw InputError(path_, "cannot write: " + write_failure(error_));
  }

private:
  void put(const char *data, std::size_t n) {
    if (n && std::fwrite(data, 1, n, file_) != n && !error_)
      error_ = errno ? errno : EIO;
  }
  void flush() {
    put(buffer_.get(), used_);
    used_ = 0;
  }

  static constexpr std::size_t kBuffer = std::size_t(4) << 20;
  std::string path_;
  std::FILE *file_;
  std::unique_ptr<char[]> buffer_ = std::make_unique_for_overwrite<char[]>(kBuffer);
  std::size_t used_ = 0;
  int error_ = 0;
};

// The arrays of `mesh` must have the sizes the Mesh contract promises.
void check_writable(const std::string &path, const Mesh &mesh) {
  if (mesh.dim == 4)
    throw InputError(path, "a .msh file cannot hold a 4D mesh; write .vtu");
  if (mesh.dim != 2 && mesh.dim != 3)
    throw InputError(path,
                     "cannot write a mesh of dimension " + std::to_string(mesh.dim) + " to .msh");
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  if (mesh.coords.size() != nv * std::size_t(mesh.dim) ||
      mesh.cells.size() != nc * std::size_t(mesh.cell_size()))
    throw InputError(path, "mesh arrays have inconsistent sizes");
  if (nv > std::size_t(INT_MAX) || nc > std::size_t(INT_MAX))
    throw InputError(path, "too many vertices or cells for a .msh file (at most 2^31 - 1)");
  for (VertexId v : mesh.cells)
    if (v >= nv)
      throw InputError(path, "a cell refers to vertex " + std::to_string(v) + " of " +
                                 std::to_string(nv));
  auto check = [&](const DataArray &a, std::size_t n, const char *kind) {
    if (a.components < 1 || a.values.size() != n * std::size_t(a.components))
      throw InputError(path, std::string(kind) + " array " + quoted(a.name) + " has " +
                                 std::to_string(a.values.size()) + " values for " +
                                 std::to_string(n) + " entities");
    if (a.name.find_first_of("\r\n") != std::string::npos)
      throw InputError(path, std::string(kind) + " array name " + quoted(a.name) +
                                 " contains a line break");
  };
  for (const DataArray &a : mesh.point_data)
    check(a, nv, "point");
  for (const DataArray &a : mesh.cell_data)
    check(a, nc, "cell");
  std::size_t elements = nc;
  for (const Entities &b : mesh.entities) {
    if (b.dim < 0 || b.dim >= mesh.dim || b.vertices.size() % std::size_t(b.dim + 1))
      throw InputError(path, "a block of tagged entities of dimension " + std::to_string(b.dim) +
                                 " is malformed");
    for (VertexId v : b.vertices)
      if (v >= nv)
        throw InputError(path, "a tagged entity refers to vertex " + std::to_string(v) + " of " +
                                   std::to_string(nv));
    for (const DataArray &a : b.data)
      check(a, b.size(), "entity");
    elements += b.size();
  }
  if (elements > std::size_t(INT_MAX))
    throw InputError(path, "too many elements for a .msh file (at most 2^31 - 1)");
  for (const PhysicalName &n : mesh.physical_names)
    if (n.name.find_first_of("\r\n\"") != std::string::npos)
      throw InputError(path, "physical name " + quoted(n.name) +
                                 " contains a line break or a double quote");
}

// A scalar cell array that becomes Gmsh entity information, or null.
const DataArray *entity_array(const std::vector<DataArray> &arrays, const std::string &name) {
  for (const DataArray &a : arrays)
    if (a.name == name && a.components == 1)
      return &a;
  return nullptr;
}

long long tag_value(const std::string &path, const DataArray *a, std::size_t c, const char *what) {
  if (!a)
    return 0;
  const double v = a->values[c];
  if (!(v == std::floor(v)) || v < INT_MIN || v > INT_MAX)
    throw InputError(path, std::string(what) + " array " + quoted(a->name) + " holds " +
                               std::to_string(v) + " at " + what + " " + std::to_string(c) +
                               ", which is not an integer tag");
  return (long long)v;
}

// The simplices of one dimension that go into the file: the cells, or one
// block of tagged entities. Element tags are first_tag + 1, first_tag + 2, ...
struct SimplexSet {
  int dim = 0;
  std::size_t count = 0;
  const VertexId *ids = nullptr; // dim+1 per simplex
  const DataArray *geom = nullptr, *phys = nullptr;
  std::size_t first_tag = 0;
  const char *what = "cell"; // names a simplex in errors
};

struct Entity {
  long long tag = 0;
  long long physical = 0; // 0: none
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
  double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
};

struct Block {
  std::size_t entity;
  std::size_t first, count; // positions in EntityPlan::order
};

struct EntityPlan {
  std::vector<Entity> entities;
  std::vector<Block> blocks;
  // The cells in file order: grouped by entity, entities in order of first
  // appearance, cells of one entity in mesh order (empty: one entity, the
  // cells in mesh order). Element tags are file positions plus one, and
  // $ElementData lists the cells in file order with those tags (meshio
  // pairs data with elements by position and wants the tags 1, 2, ...):
  // readers that go by tags, Gmsh and ours, get the cells in file order.
  std::vector<std::size_t> order;
};

// One entity per distinct (geometrical, physical) pair, tagged with the
// geometrical tag unless another pair already took it; one element block per
// entity, as Gmsh itself writes them.
EntityPlan plan_entities(const std::string &path, const Mesh &mesh, const SimplexSet &set) {
  EntityPlan plan;
  const std::size_t nc = set.count;
  const DataArray *geom = set.geom, *phys = set.phys;
  const int nvs = set.dim + 1;
  long long next_tag = 1;
  if (nc == 0)
    return plan;
  // Tags are checked where they change from the cell before (a NaN always
  // does): the first bad one is still the one reported.
  if (geom)
    for (std::size_t c = 0; c < nc; ++c)
      if (c == 0 || !(geom->values[c] == geom->values[c - 1]))
        next_tag = std::max(next_tag, tag_value(path, geom, c, set.what) + 1);
  std::map<std::pair<long long, long long>, std::size_t> entity_of;
  std::set<long long> taken;
  const auto entity_of_cell = std::make_unique_for_overwrite<std::uint32_t[]>(nc);
  // Cells come in runs of one (geometrical, physical) pair: the map is asked
  // when the pair changes, not for every cell (10.8 M tets of one entity:
  // a fifth of the .msh write's time went to the map and to reading every
  // cell's points for the boxes).
  std::size_t last = std::size_t(-1);
  double last_g = 0, last_p = 0;
  // The box of an entity takes each vertex once in a row: in_box[v] is the
  // last entity whose box took v (nobody: kNoEntity).
  constexpr std::uint32_t kNoEntity = std::uint32_t(-1);
  std::vector<std::uint32_t> in_box(mesh.num_vertices(), kNoEntity);
  for (std::size_t c = 0; c < nc; ++c) {
    const double gv = geom ? geom->values[c] : 0.0, pv = phys ? phys->values[c] : 0.0;
    if (last == std::size_t(-1) || !(gv == last_g) || !(pv == last_p)) {
      const long long g = tag_value(path, geom, c, set.what),
                      p = tag_value(path, phys, c, set.what);
      auto [it, added] = entity_of.emplace(std::make_pair(g, p), plan.entities.size());
      if (added) {
        Entity e;
        e.tag = geom && !taken.count(g) ? g : next_tag++;
        if (e.tag > INT_MAX)
          throw InputError(path, "too many distinct gmsh:geometrical / gmsh:physical pairs");
        e.physical = p;
        taken.insert(e.tag);
        plan.entities.push_back(e);
      }
      last = it->second;
      last_g = gv;
      last_p = pv;
    }
    Entity &e = plan.entities[last];
    for (int k = 0; k < nvs; ++k) {
      const VertexId v = set.ids[c * std::size_t(nvs) + std::size_t(k)];
      if (in_box[v] == std::uint32_t(last))
        continue;
      in_box[v] = std::uint32_t(last);
      const double *x = mesh.point(v);
      for (int i = 0; i < 3; ++i) {
        const double xi = i < mesh.dim ? x[i] : 0.0;
        e.lo[i] = std::min(e.lo[i], xi);
        e.hi[i] = std::max(e.hi[i], xi);
      }
    }
    entity_of_cell[c] = std::uint32_t(last);
  }
  // One entity: the cells in mesh order (order stays empty).
  if (plan.entities.size() == 1) {
    plan.blocks.push_back({0, 0, nc});
    return plan;
  }
  // Counting sort of the cells by entity.
  std::vector<std::size_t> count(plan.entities.size(), 0);
  for (std::size_t c = 0; c < nc; ++c)
    ++count[entity_of_cell[c]];
  std::vector<std::size_t> next;
  for (std::size_t e = 0, first = 0; e < plan.entities.size(); first += count[e], ++e) {
    plan.blocks.push_back({e, first, count[e]});
    next.push_back(first);
  }
  plan.order.resize(nc);
  for (std::size_t c = 0; c < nc; ++c)
    plan.order[next[entity_of_cell[c]]++] = c;
  return plan;
}

// plans[d]: the Gmsh entities of dimension d (points have a point, not a box).
void write_entities(Output &out, const EntityPlan *const plans[4]) {
  out.text("$Entities\n");
  for (int d = 0; d < 4; ++d)
    out.size(plans[d] ? plans[d]->entities.size() : 0);
  for (int d = 0; d < 4; ++d) {
    if (!plans[d])
      continue;
    // Where some entities of a dimension have a physical tag and others
    // none (gmsh:physical 0), those get the tag 0 written: meshio reads
    // gmsh:physical only for blocks whose entity lists a tag, and refuses a
    // file where some blocks have it and others not. Our reader and Gmsh
    // read 0 back (Gmsh as a group 0).
    const auto &all = plans[d]->entities;
    const bool some =
        std::any_of(all.begin(), all.end(), [](const Entity &e) { return e.physical != 0; });
    const bool every = some && std::all_of(all.begin(), all.end(),
                                           [](const Entity &e) { return e.physical != 0; });
    const bool write_zero = some && !every;
    for (const Entity &e : all) {
      out.int32(e.tag);
      for (double x : e.lo)
        out.raw<double>(x);
      if (d > 0)
        for (double x : e.hi)
          out.raw<double>(x);
      const bool tagged = e.physical != 0 || write_zero;
      out.size(tagged ? 1 : 0);
      if (tagged)
        out.int32(e.physical);
      if (d > 0)
        out.size(0); // no bounding entities
    }
  }
  out.text("\n$EndEntities\n");
}

// A 2D mesh's z (kPlaneZArray), which goes into the nodes; null if none.
const DataArray *plane_z_of(const Mesh &mesh) {
  if (mesh.dim != 2)
    return nullptr;
  for (const DataArray &a : mesh.point_data)
    if (a.name == kPlaneZArray && a.components == 1)
      return &a;
  return nullptr;
}

void write_nodes(Output &out, const Mesh &mesh, long long entity) {
  const std::size_t nv = mesh.num_vertices();
  const DataArray *plane_z = plane_z_of(mesh);
  out.text("$Nodes\n");
  out.size(nv ? 1 : 0);
  out.size(nv);
  out.size(nv ? 1 : 0);
  out.size(nv);
  if (nv) {
    out.int32(mesh.dim);
    out.int32(entity);
    out.int32(0); // not parametric
    out.size(nv);
    constexpr std::size_t kRun = Output::kSpan / 24;
    for (std::size_t v0 = 0; v0 < nv; v0 += kRun) {
      const std::size_t n = std::min(kRun, nv - v0);
      char *at = out.span(n * 8);
      for (std::size_t v = v0; v < v0 + n; ++v, at += 8)
        store<std::uint64_t>(at, v + 1);
    }
    for (std::size_t v0 = 0; v0 < nv; v0 += kRun) {
      const std::size_t n = std::min(kRun, nv - v0);
      char *at = out.span(n * 24);
      for (std::size_t v = v0; v < v0 + n; ++v)
        for (int i = 0; i < 3; ++i, at += 8)
          store<double>(at, i < mesh.dim ? mesh.point(VertexId(v))[i]
                            : plane_z    ? plane_z->values[v]
                                         : 0.0);
    }
  }
  out.text("\n$EndNodes\n");
}

// The cells (sets[0]) and the entity blocks, each set's element blocks in
// its plan's order.
void write_elements(Output &out, const std::vector<SimplexSet> &sets,
                    const std::vector<EntityPlan> &plans, const std::uint8_t *flipped) {
  std::size_t blocks = 0, total = 0;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    blocks += plans[i].blocks.size();
    total += sets[i].count;
  }
  out.text("$Elements\n");
  out.size(blocks);
  out.size(total);
  out.size(total ? 1 : 0);
  out.size(total);
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const SimplexSet &set = sets[i];
    const std::size_t nvs = std::size_t(set.dim + 1);
    for (const Block &b : plans[i].blocks) {
      out.int32(set.dim);
      out.int32(plans[i].entities[b.entity].tag);
      out.int32(kSimplexType[set.dim]);
      out.size(b.count);
      const std::size_t record = 8 * (1 + nvs), run = Output::kSpan / record;
      const std::uint8_t *flip = i == 0 ? flipped : nullptr;
      for (std::size_t j0 = b.first; j0 < b.first + b.count; j0 += run) {
        const std::size_t j1 = std::min(b.first + b.count, j0 + run);
        char *at = out.span((j1 - j0) * record);
        for (std::size_t j = j0; j < j1; ++j) {
          const std::size_t c = plans[i].order.empty() ? j : plans[i].order[j];
          // Tags in file order, which meshio's binary $ElementData reader
          // needs (its rows' tags must be 1, 2, ... in order): the cells of
          // one entity, the cells' index + 1, keep the mesh's order on a
          // round trip; with several, the cells come back grouped by
          // entity. A flipped cell (stream_state) goes with its first two
          // ids swapped.
          store<std::uint64_t>(at, set.first_tag + j + 1);
          const VertexId *x = set.ids + c * nvs;
          const bool swap = flip && flip[c]; // cells only: at least 3 ids
          for (std::size_t k = 0; k < nvs; ++k)
            store<std::uint64_t>(at + 8 * (k + 1), std::uint64_t(x[swap && k < 2 ? 1 - k : k]) + 1);
          at += record;
        }
      }
    }
  }
  out.text("\n$EndElements\n");
}

// $PhysicalNames is text in binary files too.
void write_physical_names(Output &out, const std::vector<PhysicalName> &names) {
  out.text("$PhysicalNames\n" + std::to_string(names.size()) + "\n");
  for (const PhysicalName &n : names)
    out.text(std::to_string(n.dim) + " " + std::to_string(n.tag) + " \"" + n.name + "\"\n");
  out.text("$EndPhysicalNames\n");
}

// An array as the data sections read it: a DataArray's values, or a
// bisection state source's (stream_state: the cells' state written without
// storing it as arrays of doubles first).
struct Rows {
  static constexpr std::size_t kPiece = 1024;
  const std::string &name;
  int components = 1;
  const DataArray *array = nullptr;
  const ArraySource *source = nullptr;
  // Values first .. first + n - 1 into out.
  void fill(std::size_t first, std::size_t n, double *out) const {
    if (array)
      std::copy_n(array->values.data() + first, n, out);
    else if (source->fill)
      source->fill(first, n, out);
    else
      for (std::size_t i = 0; i < n; ++i)
        out[i] = source->value(first + i);
  }
};
Rows rows_of(const DataArray &a) {
  return {a.name, a.components, &a, nullptr};
}
Rows rows_of(const ArraySource &a) {
  return {a.name, a.components, nullptr, &a};
}

// Rows order[j] of `a` (j < n; row j when order is empty), or zeros for a
// null `a`, each after its tag first_tag + 1 + j. Runs of consecutive rows
// are filled at once.
void write_rows(Output &out, const Rows *a, std::size_t components, std::size_t n,
                const std::vector<std::size_t> &order, std::size_t first_tag) {
  const std::size_t nc = components, record = 4 + 8 * nc;
  std::vector<double> values(std::max(Rows::kPiece, nc));
  const std::size_t run =
      std::max<std::size_t>(1, std::min(Output::kSpan / record, values.size() / nc));
  for (std::size_t j0 = 0; j0 < n;) {
    const std::size_t first = order.empty() ? j0 : order[j0];
    std::size_t j1 = j0 + 1;
    while (j1 < n && j1 - j0 < run && (order.empty() ? j1 : order[j1]) == first + (j1 - j0))
      ++j1;
    const std::size_t rows = j1 - j0;
    if (a)
      a->fill(first * nc, rows * nc, values.data());
    else
      std::fill_n(values.data(), rows * nc, 0.0);
    auto tag = [&](std::size_t i) { return std::int32_t(first_tag + 1 + j0 + i); };
    if (record <= Output::kSpan) {
      char *at = out.span(rows * record);
      for (std::size_t i = 0; i < rows; ++i, at += record) {
        store<std::int32_t>(at, tag(i));
        std::memcpy(at + 4, values.data() + i * nc, 8 * nc);
      }
    } else {
      for (std::size_t i = 0; i < rows; ++i) {
        out.int32(tag(i));
        for (std::size_t k = 0; k < nc; ++k)
          out.raw<double>(values[i * nc + k]);
      }
    }
    j0 = j1;
  }
}

// One $NodeData/$ElementData section: time 0, time step 0. Row i is entity
// order[i] (the identity when order is empty), with tag i + 1.
void write_data(Output &out, const std::string &section, const Rows &a, std::size_t n,
                const std::vector<std::size_t> &order = {}) {
  out.text("$" + section + "\n1\n\"" + a.name + "\"\n1\n0\n3\n0\n" + std::to_string(a.components) +
           "\n" + std::to_string(n) + "\n");
  write_rows(out, &a, std::size_t(a.components), n, order, 0);
  out.text("\n$End" + section + "\n");
}

// A cell array as $ElementData. With tagged entities the section lists them
// too (meshio pairs element data with every element by position): an
// entity's own value of the array (same name and components) or 0. Readers
// that go by tags, ours included, ignore those rows.
void write_element_data(Output &out, const Rows &a, const std::vector<SimplexSet> &sets,
                        const std::vector<EntityPlan> &plans, const std::vector<Entities> &blocks) {
  if (sets.size() == 1)
    return write_data(out, "ElementData", a, sets[0].count, plans[0].order);
  std::size_t n = 0;
  for (const SimplexSet &set : sets)
    n += set.count;
  out.text("$ElementData\n1\n\"" + a.name + "\"\n1\n0\n3\n0\n" + std::to_string(a.components) +
           "\n" + std::to_string(n) + "\n");
  const std::size_t nc = std::size_t(a.components);
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (i == 0) {
      write_rows(out, &a, nc, sets[0].count, plans[0].order, sets[0].first_tag);
      continue;
    }
    // sets[i] is the block of entities whose vertices it points at
    const DataArray *own = nullptr;
    for (const Entities &b : blocks)
      if (b.vertices.data() == sets[i].ids)
        for (const DataArray &e : b.data)
          if (e.name == a.name && e.components == a.components)
            own = &e;
    if (own) {
      const Rows rows = rows_of(*own);
      write_rows(out, &rows, nc, sets[i].count, plans[i].order, sets[i].first_tag);
    } else {
      write_rows(out, nullptr, nc, sets[i].count, plans[i].order, sets[i].first_tag);
    }
  }
  out.text("\n$EndElementData\n");
}

} // namespace

Mesh read_msh(const std::string &path) {
  Source src(path);
  MshFile f = parse(src);
  src.drop_binary_text();
  return assemble(src, f);
}

void write_msh(const std::string &path, const Mesh &mesh) {
  write_msh_with_state(path, mesh, nullptr);
}

void write_msh_with_state(const std::string &path, const Mesh &mesh, const StateArrays *state) {
  check_writable(path, mesh);
  const DataArray *geom = entity_array(mesh.cell_data, "gmsh:geometrical");
  const DataArray *phys = entity_array(mesh.cell_data, "gmsh:physical");
  // The cells, then the tagged entities, lowest dimension first.
  std::vector<SimplexSet> sets{{mesh.dim, mesh.num_cells(), mesh.cells.data(), geom, phys, 0}};
  std::size_t tags = mesh.num_cells();
  std::vector<const Entities *> blocks;
  for (const Entities &b : mesh.entities)
    if (b.size() > 0)
      blocks.push_back(&b);
  std::stable_sort(blocks.begin(), blocks.end(),
                   [](const Entities *p, const Entities *q) { return p->dim < q->dim; });
  for (const Entities *b : blocks) {
    sets.push_back({b->dim, b->size(), b->vertices.data(),
                    entity_array(b->data, "gmsh:geometrical"),
                    entity_array(b->data, "gmsh:physical"), tags, "entity"});
    tags += b->size();
  }
  std::vector<EntityPlan> plans;
  for (const SimplexSet &set : sets)
    plans.push_back(plan_entities(path, mesh, set));
  // Two entity blocks of one dimension (not what the readers make) share
  // the dimension's Gmsh entities: merged into the first plan's numbering
  // would take more code than such a mesh deserves, so they are refused.
  const EntityPlan *by_dim[4] = {nullptr, nullptr, nullptr, nullptr};
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (by_dim[sets[i].dim])
      throw InputError(path, "two blocks of tagged entities of dimension " +
                                 std::to_string(sets[i].dim) + " (one per dimension)");
    by_dim[sets[i].dim] = &plans[i];
  }
  Output out(path);
  out.text("$MeshFormat\n4.1 1 8\n");
  out.int32(1); // the endianness check
  out.text("\n$EndMeshFormat\n");
  if (!mesh.physical_names.empty())
    write_physical_names(out, mesh.physical_names);
  // Without tag arrays or entities there is no $Entities: reading gives no
  // tag arrays back.
  if (geom || phys || sets.size() > 1)
    write_entities(out, by_dim);
  write_nodes(out, mesh, plans[0].entities.empty() ? 1 : plans[0].entities.front().tag);
  const std::uint8_t *flipped =
      state && state->flipped.size() == mesh.num_cells() ? state->flipped.data() : nullptr;
  write_elements(out, sets, plans, flipped);
  // The state's arrays after the mesh's own, as encode_state would add them.
  for (const DataArray &a : mesh.point_data)
    if (&a != plane_z_of(mesh) && !(state && state->hides(a.name)))
      write_data(out, "NodeData", rows_of(a), mesh.num_vertices());
  if (state)
    for (const ArraySource &a : state->points)
      write_data(out, "NodeData", rows_of(a), mesh.num_vertices());
  for (const DataArray &a : mesh.cell_data)
    if (&a != geom && &a != phys && !(state && state->hides(a.name)))
      write_element_data(out, rows_of(a), sets, plans, mesh.entities);
  if (state)
    for (const ArraySource &a : state->cells)
      write_element_data(out, rows_of(a), sets, plans, mesh.entities);
  out.close();
}

} // namespace bisect

namespace bisect::testing {
void set_msh_element_runs(bool on) {
  g_element_runs = on;
}
} // namespace bisect::testing
