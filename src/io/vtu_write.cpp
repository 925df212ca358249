// Native .vtu writer: VTK XML UnstructuredGrid, inline base64 binary
// (format="binary": what VTK, ParaView and meshio all read; meshio misreads
// raw appended data), UInt64 headers, little-endian, blocks of 32 KiB
// compressed with zlib or LZ4, or not at all. Arrays are encoded straight
// from the Mesh, one block at a time: no VTK objects, no copy of the mesh.
//
// The layout of one array (VTK's, vtkXMLWriter): uncompressed, one base64
// stream of [byte count][bytes]; compressed, the base64 of the header
// [blocks][block size][last block size][compressed size of each block]
// followed by a second base64 stream of the compressed blocks.
#include "io/vtu_write.hpp"

#include "io/huffman_deflate.hpp"

#include "bisect/output.hpp"
#include "bisect/text.hpp"
#include "bisect/threads.hpp"

#include <libdeflate.h>
#include <lz4.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <memory>
#include <numeric>
#include <set>
#include <string>
#include <sys/stat.h>
#include <vector>

namespace bisect {
namespace {

constexpr std::size_t kBlock = 32768; // VTK's default block size

constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

// The two base64 digits of every 12-bit value: a group of three bytes is
// two lookups.
struct Base64Pairs {
  std::array<std::array<char, 2>, 4096> digits;
  constexpr Base64Pairs() : digits() {
    for (unsigned v = 0; v < 4096; ++v)
      digits[v] = {kDigits[v >> 6], kDigits[v & 63]};
  }
};
constexpr Base64Pairs kPairs;

// Buffered output with base64 encoding; write errors are kept and reported
// once, naming the file.
class Writer {
public:
  explicit Writer(const std::string &path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
    if (!file_)
      throw InputError(path, "cannot write: " + write_failure(errno));
    buf_.reserve(kBuffer + 8);
    struct stat st {};
    const int fd = ::fileno(file_);
    seekable_ = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && !(::fcntl(fd, F_GETFL) & O_APPEND);
  }
  // Whether position() and patch() work (a regular file, not a pipe).
  bool seekable() const { return seekable_; }
  ~Writer() {
    if (file_)
      std::fclose(file_);
  }
  Writer(const Writer &) = delete;
  Writer &operator=(const Writer &) = delete;

  void text(const std::string &s) {
    buf_.append(s);
    if (buf_.size() >= kBuffer)
      flush();
  }

  // base64 of `n` bytes, continuing the current base64 stream. Whole groups
  // of three bytes are encoded straight into the buffer (two lookups in
  // kPairs a group), a piece of at most kBuffer characters at a time:
  // appending four characters a group, each looked up, with a size check
  // each, took ~1.6% of the 3D benchmark's 13 iterations on one thread, this
  // ~0.6%, and the encoding is serial.
  void base64(const unsigned char *p, std::size_t n) {
    while (n > 0 && carry_n_ > 0) {
      carry_[carry_n_++] = *p++;
      --n;
      if (carry_n_ == 3) {
        encode3(carry_);
        carry_n_ = 0;
      }
    }
    for (std::size_t whole = n / 3 * 3; whole > 0;) {
      const std::size_t take = std::min(whole, kBuffer / 4 * 3);
      const std::size_t at = buf_.size();
      buf_.resize(at + take / 3 * 4);
      char *out = buf_.data() + at;
      for (std::size_t i = 0; i < take; i += 3, out += 4) {
        const unsigned v = unsigned(p[i]) << 16 | unsigned(p[i + 1]) << 8 | unsigned(p[i + 2]);
        std::memcpy(out, kPairs.digits[v >> 12].data(), 2);
        std::memcpy(out + 2, kPairs.digits[v & 4095].data(), 2);
      }
      p += take;
      n -= take;
      whole -= take;
      if (buf_.size() >= kBuffer)
        flush();
    }
    for (; n > 0; --n) // at most two bytes left: the next call's first group
      carry_[carry_n_++] = *p++;
  }
  // Ends a base64 stream (with '=' padding).
  void end_base64() {
    if (carry_n_ == 1) {
      const unsigned v = unsigned(carry_[0]) << 16;
      buf_ += kDigits[v >> 18 & 63];
      buf_ += kDigits[v >> 12 & 63];
      buf_ += "==";
    } else if (carry_n_ == 2) {
      const unsigned v = unsigned(carry_[0]) << 16 | unsigned(carry_[1]) << 8;
      buf_ += kDigits[v >> 18 & 63];
      buf_ += kDigits[v >> 12 & 63];
      buf_ += kDigits[v >> 6 & 63];
      buf_ += '=';
    }
    carry_n_ = 0;
  }

  // The file offset of the next byte written (flushes the buffer).
  long position() {
    flush();
    const long at = std::ftell(file_);
    if (at < 0 && !error_)
      error_ = errno ? errno : EIO;
    return at;
  }
  // Overwrites the bytes at `at` (written earlier) with `s`; writing goes on
  // at the end. The file is always a regular temporary file (OutputSet).
  void patch(long at, const std::string &s) {
    flush();
    if (at < 0 || std::fseek(file_, at, SEEK_SET) != 0 ||
        std::fwrite(s.data(), 1, s.size(), file_) != s.size() ||
        std::fseek(file_, 0, SEEK_END) != 0)
      if (!error_)
        error_ = errno ? errno : EIO;
  }
  // The base64 text of `n` bytes (one whole stream, padded).
  static std::string base64_text(const unsigned char *p, std::size_t n) {
    std::string out;
    for (std::size_t i = 0; i < n; i += 3) {
      const std::size_t k = std::min<std::size_t>(3, n - i);
      unsigned v = unsigned(p[i]) << 16;
      if (k > 1)
        v |= unsigned(p[i + 1]) << 8;
      if (k > 2)
        v |= unsigned(p[i + 2]);
      out += kDigits[v >> 18 & 63];
      out += kDigits[v >> 12 & 63];
      out += k > 1 ? kDigits[v >> 6 & 63] : '=';
      out += k > 2 ? kDigits[v & 63] : '=';
    }
    return out;
  }

  void close() {
    flush();
    if (std::fflush(file_) != 0 && !error_)
      error_ = errno ? errno : EIO;
    if (std::fclose(file_) != 0 && !error_)
      error_ = errno ? errno : EIO;
    file_ = nullptr;
    if (error_)
      throw InputError(path_, "cannot write: " + write_failure(error_));
  }

private:
  static constexpr std::size_t kBuffer = std::size_t(1) << 20;

  void encode3(const unsigned char *p) {
    const unsigned v = unsigned(p[0]) << 16 | unsigned(p[1]) << 8 | unsigned(p[2]);
    const char out[4] = {kDigits[v >> 18 & 63], kDigits[v >> 12 & 63], kDigits[v >> 6 & 63],
                         kDigits[v & 63]};
    buf_.append(out, 4);
    if (buf_.size() >= kBuffer)
      flush();
  }
  void flush() {
    if (!buf_.empty() && std::fwrite(buf_.data(), 1, buf_.size(), file_) != buf_.size() && !error_)
      error_ = errno ? errno : EIO;
    buf_.clear();
  }

  std::string path_;
  std::FILE *file_;
  std::string buf_;
  unsigned char carry_[3] = {0, 0, 0};
  int carry_n_ = 0;
  int error_ = 0;
  bool seekable_ = false;
};

std::string xml_escaped(const std::string &s) {
  std::string out;
  for (char c : s) {
    switch (c) {
    case '&':
      out += "&amp;";
      break;
    case '<':
      out += "&lt;";
      break;
    case '>':
      out += "&gt;";
      break;
    case '"':
      out += "&quot;";
      break;
    case '\'':
      out += "&apos;";
      break;
    default:
      out += c;
    }
  }
  return out;
}

// How a group's blocks after its first are compressed in zlib's format:
// deflate at the writer's level, stored, or as literals alone with their
// own Huffman code (huffman_deflate.hpp). Decided by the group's first
// block, deflated: stored when deflate shrinks it by less than a tenth,
// literals when their code comes within a quarter of deflate's size.
enum class Coding { Deflate, Stored, Literals };

// A libdeflate compressor, freed with its own function.
struct Deflater {
  void operator()(libdeflate_compressor *c) const { libdeflate_free_compressor(c); }
};

template <class T> const char *type_name();
template <> const char *type_name<double>() {
  return "Float64";
}
template <> const char *type_name<std::int32_t>() {
  return "Int32";
}
template <> const char *type_name<std::int64_t>() {
  return "Int64";
}
template <> const char *type_name<std::uint8_t>() {
  return "UInt8";
}
template <> const char *type_name<std::int8_t>() {
  return "Int8";
}
template <> const char *type_name<std::int16_t>() {
  return "Int16";
}
template <> const char *type_name<std::uint16_t>() {
  return "UInt16";
}
template <> const char *type_name<std::uint32_t>() {
  return "UInt32";
}
template <> const char *type_name<std::uint64_t>() {
  return "UInt64";
}
template <> const char *type_name<float>() {
  return "Float32";
}

// Writes one DataArray element: `count` values of T, value(i) for the i-th
// (called from several threads when compressing: it must only read).
// An array's values given a block at a time: fill(first, n, out) writes
// values first .. first + n - 1 to out (any of the array types: `out` is
// T *). The per-value form, value(i), fills a block one call and one
// store at a time; with it, the fills (a std::function call per value of
// the state's arrays, a branch and a division per id of the connectivity,
// a push_back() per value) were a fifth of the profile samples in the
// write stage's time window (Gmsh's 3D ball, 14 iterations, 31 M tets, one
// thread).
template <class Fill> struct Bulk { Fill fill; };
template <class Fill> Bulk(Fill) -> Bulk<Fill>;

template <class T, class Value>
void fill_block(const Value &value, std::size_t first, std::size_t n, T *out) {
  for (std::size_t i = 0; i < n; ++i)
    out[i] = value(first + i);
}
template <class T, class Fill>
void fill_block(const Bulk<Fill> &bulk, std::size_t first, std::size_t n, T *out) {
  bulk.fill(first, n, out);
}

// Source a's values first .. first + n - 1, as T.
template <class T>
void fill_source(const ArraySource &a, std::size_t first, std::size_t n, T *out) {
  if (!a.fill) {
    for (std::size_t i = 0; i < n; ++i)
      out[i] = static_cast<T>(a.value(first + i));
    return;
  }
  constexpr std::size_t kPiece = 1024;
  double piece[kPiece];
  for (std::size_t at = 0; at < n; at += kPiece) {
    const std::size_t m = std::min(kPiece, n - at);
    a.fill(first + at, m, piece);
    for (std::size_t i = 0; i < m; ++i)
      out[at + i] = static_cast<T>(piece[i]);
  }
}
// A source as a Bulk for write_values().
auto bulk(const ArraySource &a) {
  return Bulk{[&a](std::size_t first, std::size_t n, auto *out) { fill_source(a, first, n, out); }};
}

template <class T, class Value>
void write_array(Writer &w, VtuCompression compression, int level, const std::string &name,
                 int components, std::size_t count, Value value, const char *extra = "") {
  w.text("        <DataArray type=\"" + std::string(type_name<T>()) + "\" Name=\"" +
         xml_escaped(name) + "\"" +
         (components > 1 ? " NumberOfComponents=\"" + std::to_string(components) + "\""
                         : std::string()) +
         extra + " format=\"binary\">\n          ");
  const std::size_t bytes = count * sizeof(T);
  const std::size_t per_block = kBlock / sizeof(T);
  if (compression == VtuCompression::None) {
    const std::uint64_t header = bytes;
    w.base64(reinterpret_cast<const unsigned char *>(&header), sizeof header);
    const auto raw = std::make_unique_for_overwrite<T[]>(std::min(count, per_block));
    for (std::size_t first = 0; first < count; first += per_block) {
      const std::size_t n = std::min(count - first, per_block);
      fill_block(value, first, n, raw.get());
      w.base64(reinterpret_cast<const unsigned char *>(raw.get()), n * sizeof(T));
    }
    w.end_base64();
  } else {
    const std::size_t blocks = (bytes + kBlock - 1) / kBlock;
    std::vector<std::uint64_t> header{blocks, kBlock,
                                      bytes % kBlock ? bytes % kBlock : (blocks ? kBlock : 0)};
    // The header (with every block's compressed size) comes first: write it
    // with sizes 0, stream the blocks, then write it again in place (its
    // base64 text has the same length), so no compressed copy of the whole
    // array is held (for the connectivity of a large mesh, ~30 bytes a cell).
    // Into a pipe (-o -) the compressed blocks are held until the header is
    // written.
    const bool stream = w.seekable();
    const long header_at = stream ? w.position() : -1;
    header.resize(3 + blocks, 0);
    if (stream) {
      w.base64(reinterpret_cast<const unsigned char *>(header.data()),
               header.size() * sizeof(std::uint64_t));
      w.end_base64();
    }
    // Blocks are filled and compressed kGroup at a time by all threads, each
    // block on its own (so the bytes do not depend on the thread count), and
    // written in order.
    //
    // In zlib's format, a group whose first block deflate shrinks by less
    // than a tenth (the coordinates of a refined mesh: 0.95 of their size)
    // stores its other blocks as they are (libdeflate's level 0: a stored
    // deflate block, which every zlib reader takes). Deflate spent 0.135 s
    // on the 3.2 M-tet ball's Points to save 5% of 13.7 MB. The choice
    // rests on the data alone, so it does not depend on the threads either.
    // A group whose first block's bytes, each coded alone with a Huffman
    // code of their own, come within a quarter of deflate's size has its
    // other blocks so coded (Coding::Literals): deflate's search for
    // matches finds few in a refined mesh's connectivity (0.66 of its size
    // at ~100 MB/s on this project's machine, timed in a scratch harness)
    // and the literals alone make 0.78 of it at ~450 MB/s.
    //
    // One thread encodes and writes group g - 1 while the others compress
    // group g (two sets of block buffers), so the serial base64 and write
    // overlap the compression.
    constexpr std::size_t kGroup = 64;
    std::vector<std::vector<unsigned char>> out[2];
    out[0].resize(std::min(blocks, kGroup));
    out[1].resize(std::min(blocks, kGroup));
    std::vector<unsigned char> packed;
    const int workers = int(std::clamp<std::size_t>(blocks / 8, 1, std::size_t(threads())));
    // One libdeflate compressor per thread and level for the whole array
    // (zlib's compress2 set up and cleared its tables for every 32 KiB block).
    using DeflaterPtr = std::unique_ptr<libdeflate_compressor, Deflater>;
    std::vector<DeflaterPtr> deflaters(static_cast<std::size_t>(workers));
    std::vector<DeflaterPtr> storers(static_cast<std::size_t>(workers));
    // Group [g0, g1)'s blocks, compressed into `done`, into the file.
    auto put = [&](std::size_t g0, std::size_t g1,
                   const std::vector<std::vector<unsigned char>> &done) {
      for (std::size_t b = g0; b < g1; ++b) {
        const std::vector<unsigned char> &tmp = done[b - g0];
        header[3 + b] = tmp.size();
        if (stream)
          w.base64(tmp.data(), tmp.size());
        else
          packed.insert(packed.end(), tmp.begin(), tmp.end());
      }
    };
    std::size_t pending = blocks; // first block of the group compressed, not yet written (none)
    for (std::size_t g0 = 0; g0 < blocks; g0 += kGroup) {
      const std::size_t g1 = std::min(blocks, g0 + kGroup);
      std::vector<std::vector<unsigned char>> &fill = out[(g0 / kGroup) % 2];
      const std::vector<std::vector<unsigned char>> &done = out[(g0 / kGroup + 1) % 2];
      bool failed = false;
      Coding coding = Coding::Deflate;
#pragma omp parallel num_threads(workers)
      {
        const auto raw = std::make_unique_for_overwrite<T[]>(per_block);
        const std::size_t me = std::size_t(omp_get_thread_num());
        auto compress = [&](std::size_t b, Coding how) {
          const std::size_t first = b * per_block, values = std::min(count - first, per_block);
          fill_block(value, first, values, raw.get());
          const auto *src = reinterpret_cast<const unsigned char *>(raw.get());
          const std::size_t n = values * sizeof(T);
          std::vector<unsigned char> &tmp = fill[b - g0];
          if (how == Coding::Literals) {
            huffman_deflate::zlib_compress(src, n, tmp);
            return;
          }
          if (compression == VtuCompression::Zlib) {
            const bool stored = how == Coding::Stored;
            DeflaterPtr &deflater = stored ? storers[me] : deflaters[me];
            if (!deflater)
              deflater.reset(libdeflate_alloc_compressor(stored ? 0 : level));
            if (!deflater) {
              failed = true;
              return;
            }
            tmp.resize(libdeflate_zlib_compress_bound(deflater.get(), n));
            const std::size_t got =
                libdeflate_zlib_compress(deflater.get(), src, n, tmp.data(), tmp.size());
            if (got == 0)
              failed = true;
            tmp.resize(got);
            return;
          }
          const int room = LZ4_compressBound(int(n));
          tmp.resize(std::size_t(room));
          const int got = LZ4_compress_default(reinterpret_cast<const char *>(src),
                                               reinterpret_cast<char *>(tmp.data()), int(n), room);
          if (got <= 0)
            failed = true;
          tmp.resize(std::size_t(std::max(got, 0)));
        };
        const bool probe = compression == VtuCompression::Zlib && level > 0 && g1 - g0 > 1;
        if (probe) {
#pragma omp single
          {
            compress(g0, Coding::Deflate);
            const std::size_t n = std::min(bytes - g0 * kBlock, kBlock);
            if (!failed && 10 * fill[0].size() > 9 * n)
              coding = Coding::Stored;
            else if (!failed && 4 * huffman_deflate::zlib_size(
                                        reinterpret_cast<const unsigned char *>(raw.get()), n) <=
                                    5 * fill[0].size())
              coding = Coding::Literals;
          }
        }
#pragma omp single nowait
        if (pending < g0)
          put(pending, g0, done);
#pragma omp for schedule(dynamic, 1)
        for (std::size_t b = g0 + (probe ? 1 : 0); b < g1; ++b)
          compress(b, coding);
      }
      if (failed)
        throw CheckError(std::string(compression == VtuCompression::Zlib ? "zlib" : "LZ4") +
                         " failed to compress array '" + name + "'");
      pending = g0;
    }
    if (pending < blocks)
      put(pending, blocks, out[(pending / kGroup) % 2]);
    if (stream) {
      w.end_base64();
      w.patch(header_at, Writer::base64_text(reinterpret_cast<const unsigned char *>(header.data()),
                                             header.size() * sizeof(std::uint64_t)));
    } else {
      w.base64(reinterpret_cast<const unsigned char *>(header.data()),
               header.size() * sizeof(std::uint64_t));
      w.end_base64();
      w.base64(packed.data(), packed.size());
      w.end_base64();
    }
  }
  w.text("\n        </DataArray>\n");
}

// Integer-valued cell arrays (tags, ids, the bisection state) are written as
// Int32, the rest as Float64 (as the VTK-based writer did).
bool fits_int32(const std::vector<double> &values) {
  for (double v : values)
    if (!(v >= std::numeric_limits<std::int32_t>::min() &&
          v <= std::numeric_limits<std::int32_t>::max() && v == std::trunc(v)))
      return false;
  return true;
}

// Writes `count` values get(i) as an array of type `t`; Unknown: Int32 when
// `int32` (the caller found every value a 32-bit integer), else Float64.
template <class Get>
void write_values(Writer &w, VtuCompression compression, int level, const std::string &name,
                  int components, std::size_t count, ValueType t, bool int32, Get get) {
  auto put = [&]<class T>(T) {
    if constexpr (requires { get.fill; })
      write_array<T>(w, compression, level, name, components, count, get);
    else
      write_array<T>(w, compression, level, name, components, count,
                     [&](std::size_t i) { return static_cast<T>(get(i)); });
  };
  switch (t) {
  case ValueType::Float32:
    return put(float{});
  case ValueType::Float64:
    return put(double{});
  case ValueType::Int8:
    return put(std::int8_t{});
  case ValueType::UInt8:
    return put(std::uint8_t{});
  case ValueType::Int16:
    return put(std::int16_t{});
  case ValueType::UInt16:
    return put(std::uint16_t{});
  case ValueType::Int32:
    return put(std::int32_t{});
  case ValueType::UInt32:
    return put(std::uint32_t{});
  case ValueType::Int64:
    return put(std::int64_t{});
  case ValueType::UInt64:
    return put(std::uint64_t{});
  case ValueType::Unknown:
    break;
  }
  if (int32)
    return put(std::int32_t{});
  put(double{});
}

// The type `values` are written in: `t`, unless an integer type cannot hold
// them all (values made by a tool: a sum of Int8 counts past 127, the mean
// of two labels), then the first wider one that can: Int32, Int64, else
// Float64. A static_cast wrapped them (127 + 1 written as -128).
ValueType holding(ValueType t, const std::vector<double> &values) {
  if (!is_integer_type(t) || values.empty())
    return t;
  double lo = values[0], hi = values[0];
  bool whole = true;
  for (double v : values) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    whole &= v == std::trunc(v);
  }
  if (!whole || !std::isfinite(lo) || !std::isfinite(hi))
    return ValueType::Float64;
  auto fits = [&](ValueType u) {
    switch (u) {
    case ValueType::Int8:
      return lo >= -128 && hi <= 127;
    case ValueType::UInt8:
      return lo >= 0 && hi <= 255;
    case ValueType::Int16:
      return lo >= -32768 && hi <= 32767;
    case ValueType::UInt16:
      return lo >= 0 && hi <= 65535;
    case ValueType::Int32:
      return lo >= -2147483648.0 && hi <= 2147483647.0;
    case ValueType::UInt32:
      return lo >= 0 && hi <= 4294967295.0;
    case ValueType::Int64:
      return lo >= -9223372036854775808.0 && hi < 9223372036854775808.0;
    case ValueType::UInt64:
      return lo >= 0 && hi < 18446744073709551616.0;
    default:
      return false;
    }
  };
  for (ValueType u : {t, ValueType::Int32, ValueType::Int64})
    if (fits(u))
      return u;
  return ValueType::Float64;
}

// Writes `a` in its type (ValueType, widened where it cannot hold a value:
// holding()); Unknown: Int32 when every value is a 32-bit integer and
// `guess_int` (cell arrays), else Float64.
void write_typed(Writer &w, VtuCompression compression, int level, const DataArray &a,
                 bool guess_int) {
  write_values(w, compression, level, a.name, a.components, a.values.size(),
               holding(a.type, a.values),
               guess_int && a.type == ValueType::Unknown && fits_int32(a.values),
               Bulk{[&](std::size_t first, std::size_t n, auto *out) {
                 using T = std::remove_pointer_t<decltype(out)>;
                 for (std::size_t i = 0; i < n; ++i)
                   out[i] = static_cast<T>(a.values[first + i]);
               }});
}

// The cell arrays of a mesh with tagged entities, which follow the volume
// cells as lower-dimensional cells of the grid: every array of the cells or
// of some entity block, with a row per cell and per entity. An entity's own
// value where its block has the array (same components), else 0 for an
// integer array (bisect:state and the other state arrays included) and NaN
// for a float one; cells lacking an entity array get the same padding. Read
// in place from the cells' and the blocks' arrays, one array at a time (a
// padded copy of every cell array would add 8 bytes per cell and array to
// the write's memory peak).
void write_cell_arrays_with_entities(Writer &w, VtuCompression compression, int level,
                                     const Mesh &mesh, const StateArrays *state) {
  std::vector<const DataArray *> firsts; // one per name, cells' arrays first
  auto note = [&](const DataArray &a) {
    if (state && state->hides(a.name))
      return;
    for (const DataArray *f : firsts)
      if (f->name == a.name)
        return;
    firsts.push_back(&a);
  };
  for (const DataArray &a : mesh.cell_data)
    note(a);
  for (const Entities &b : mesh.entities)
    for (const DataArray &a : b.data)
      note(a);
  auto same_array = [](const std::vector<DataArray> &arrays, const DataArray &like) {
    for (const DataArray &a : arrays)
      if (a.name == like.name && a.components == like.components)
        return &a;
    return static_cast<const DataArray *>(nullptr);
  };
  struct Segment {
    const DataArray *own;     // nullptr: padding
    std::size_t first, count; // values
  };
  for (const DataArray *f : firsts) {
    const bool integer =
        is_integer_type(f->type) || (f->type == ValueType::Unknown && fits_int32(f->values));
    const double pad = integer ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    const std::size_t k = std::size_t(f->components);
    std::vector<Segment> segments;
    std::size_t total = 0;
    auto add = [&](const DataArray *own, std::size_t rows) {
      segments.push_back({own, total, rows * k});
      total += rows * k;
    };
    add(same_array(mesh.cell_data, *f), mesh.num_cells());
    for (const Entities &b : mesh.entities)
      add(same_array(b.data, *f), b.size());
    // NaN padding must not be guessed as Int32.
    ValueType type = f->type == ValueType::Unknown && !integer ? ValueType::Float64 : f->type;
    for (const Segment &s : segments)
      if (s.own)
        type = holding(type, s.own->values);
    // Blocks are encoded by several threads: each block finds its segments
    // (a handful) by itself.
    write_values(w, compression, level, f->name, f->components, total, type,
                 type == ValueType::Unknown, Bulk{[&](std::size_t first, std::size_t n, auto *out) {
                   using T = std::remove_pointer_t<decltype(out)>;
                   const std::size_t end = first + n;
                   for (const Segment &s : segments) {
                     const std::size_t lo = std::max(first, s.first),
                                       hi = std::min(end, s.first + s.count);
                     for (std::size_t i = lo; i < hi; ++i)
                       out[i - first] = static_cast<T>(s.own ? s.own->values[i - s.first] : pad);
                   }
                 }});
  }
  // The state's arrays (integers): the cells' values, then 0 for every
  // entity, as a stored state array would be padded.
  if (state) {
    const std::size_t ncells = mesh.num_cells();
    std::size_t rows = ncells;
    for (const Entities &b : mesh.entities)
      rows += b.size();
    for (const ArraySource &a : state->cells) {
      const std::size_t k = std::size_t(a.components);
      write_values(w, compression, level, a.name, a.components, rows * k, a.type, false,
                   Bulk{[&](std::size_t first, std::size_t n, auto *out) {
                     const std::size_t own = std::min(first + n, std::max(first, ncells * k));
                     fill_source(a, first, own - first, out);
                     std::fill(out + (own - first), out + n, 0);
                   }});
    }
  }
}

// Physical names as field data in meshio's convention: an Int32 array named
// after the group, holding (tag, dimension). Gmsh lets groups of two
// dimensions share a name (a 2D and a 3D "domain"), but VTK keeps one field
// array of a name (and our reader refuses two): the group of the highest
// dimension keeps the name (as in meshio's conversion, which keeps the
// last of Gmsh's list), and the others are written as "domain (2D, tag 7)",
// as is a group named SpatialDimension. A group listed twice is written once.
void write_physical_names(Writer &w, VtuCompression compression, int level, const Mesh &mesh) {
  const std::vector<PhysicalName> &all = mesh.physical_names;
  std::vector<std::size_t> by_dim(all.size());
  std::iota(by_dim.begin(), by_dim.end(), std::size_t(0));
  std::stable_sort(by_dim.begin(), by_dim.end(),
                   [&](std::size_t a, std::size_t b) { return all[a].dim > all[b].dim; });
  std::set<std::string> taken{"SpatialDimension"};
  std::set<std::pair<int, int>> groups;
  std::vector<std::string> names(all.size()); // empty: not written
  for (std::size_t i : by_dim) {
    const PhysicalName &n = all[i];
    if (!groups.insert({n.dim, n.tag}).second)
      continue;
    std::string name = n.name;
    if (taken.count(name))
      name += " (" + std::to_string(n.dim) + "D, tag " + std::to_string(n.tag) + ")";
    if (taken.insert(name).second) // else only a name made to collide: no name
      names[i] = std::move(name);
  }
  for (std::size_t i = 0; i < all.size(); ++i)
    if (!names[i].empty())
      write_array<std::int32_t>(
          w, compression, level, names[i], 1, 2,
          [&](std::size_t k) { return std::int32_t(k == 0 ? all[i].tag : all[i].dim); },
          " NumberOfTuples=\"2\"");
}

} // namespace

void check_names(const Mesh &mesh, const std::string &path) {
  auto check = [&](const std::string &name, const char *what) {
    if (!is_name_text(name))
      throw InputError(path, std::string(what) + " '" + shown_name(name) +
                                 "' is not UTF-8 text without control characters");
  };
  for (const DataArray &a : mesh.point_data)
    check(a.name, "point array name");
  for (const DataArray &a : mesh.cell_data)
    check(a.name, "cell array name");
  for (const Entities &b : mesh.entities)
    for (const DataArray &a : b.data)
      check(a.name, "array name");
  for (const PhysicalName &n : mesh.physical_names)
    check(n.name, "physical name");
}

void write_vtu_native(const std::string &path, const Mesh &mesh, VtuCompression compression,
                      int level, const StateArrays *state) {
  const std::size_t nv = mesh.num_vertices(), ncells = mesh.num_cells();
  const int dim = mesh.dim, nvc = dim + 1;
  // Tagged entities are cells of the grid after the volume cells.
  std::size_t nentities = 0, entity_ids = 0;
  for (const Entities &b : mesh.entities) {
    nentities += b.size();
    entity_ids += b.vertices.size();
  }
  const std::size_t nc = ncells + nentities;
  check_names(mesh, path);
  Writer w(path);
  w.text("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
         "byte_order=\"LittleEndian\" header_type=\"UInt64\"");
  if (compression == VtuCompression::Zlib)
    w.text(" compressor=\"vtkZLibDataCompressor\"");
  if (compression == VtuCompression::Lz4)
    w.text(" compressor=\"vtkLZ4DataCompressor\"");
  w.text(">\n  <UnstructuredGrid>\n");
  if (dim == 4 || !mesh.physical_names.empty()) {
    w.text("    <FieldData>\n");
    if (dim == 4)
      write_array<std::int32_t>(
          w, compression, level, "SpatialDimension", 1, 1,
          [](std::size_t) { return std::int32_t(4); }, " NumberOfTuples=\"1\"");
    write_physical_names(w, compression, level, mesh);
    w.text("    </FieldData>\n");
  }
  w.text("    <Piece NumberOfPoints=\"" + std::to_string(nv) + "\" NumberOfCells=\"" +
         std::to_string(nc) + "\">\n      <PointData>\n");
  // A 2D mesh's z (kPlaneZArray) goes into the points, not into an array.
  const DataArray *plane_z = nullptr;
  for (const DataArray &a : mesh.point_data) {
    if (dim == 2 && a.name == kPlaneZArray && a.components == 1) {
      plane_z = &a;
      continue;
    }
    if (state && state->hides(a.name))
      continue;
    write_typed(w, compression, level, a, false);
  }
  if (state)
    for (const ArraySource &a : state->points)
      write_values(w, compression, level, a.name, a.components, nv * std::size_t(a.components),
                   a.type, false, bulk(a));
  if (dim == 4)
    write_array<double>(w, compression, level, "t", 1, nv,
                        [&](std::size_t v) { return mesh.coords[v * 4 + 3]; });
  w.text("      </PointData>\n      <CellData>\n");
  if (nentities == 0) {
    for (const DataArray &a : mesh.cell_data)
      if (!state || !state->hides(a.name))
        write_typed(w, compression, level, a, true);
    if (state)
      for (const ArraySource &a : state->cells)
        write_values(w, compression, level, a.name, a.components,
                     ncells * std::size_t(a.components), a.type, false, bulk(a));
  } else {
    write_cell_arrays_with_entities(w, compression, level, mesh, state);
  }
  w.text("      </CellData>\n      <Points>\n");
  write_array<double>(w, compression, level, "Points", 3, 3 * nv,
                      Bulk{[&](std::size_t first, std::size_t n, double *out) {
                        for (std::size_t i = first; i < first + n; ++i) {
                          const std::size_t v = i / 3, k = i % 3;
                          out[i - first] = int(k) < dim ? mesh.coords[v * std::size_t(dim) + k]
                                           : plane_z    ? plane_z->values[v]
                                                        : 0.0;
                        }
                      }});
  w.text("      </Points>\n      <Cells>\n");
  // The entities' ids, offsets and types in grid order (only when there are any).
  std::vector<std::int64_t> entity_conn, entity_offsets;
  std::vector<std::uint8_t> entity_types;
  entity_conn.reserve(entity_ids);
  std::int64_t end = std::int64_t(mesh.cells.size());
  for (const Entities &b : mesh.entities) {
    static const std::uint8_t kSimplexType[4] = {1, 3, 5, 10}; // vertex, line, triangle, tetra
    for (std::size_t i = 0; i < b.size(); ++i) {
      for (int k = 0; k <= b.dim; ++k)
        entity_conn.push_back(std::int64_t(b.entity(i)[k]));
      end += b.dim + 1;
      entity_offsets.push_back(end);
      entity_types.push_back(kSimplexType[b.dim]);
    }
  }
  const std::size_t ncell_ids = mesh.cells.size();
  // The cells stream_state orients by swapping their first two ids (the
  // mesh itself is left as it is).
  const std::uint8_t *flipped =
      state && state->flipped.size() == ncells ? state->flipped.data() : nullptr;
  // Ids first .. first + n - 1 of the grid's connectivity: the cells' as
  // they are, then those of the flipped cells among them swapped, then the
  // entities'.
  auto connectivity_ids = [&](std::size_t first, std::size_t n, auto *out) {
    using T = std::remove_pointer_t<decltype(out)>;
    const std::size_t end = first + n, own = std::min(end, std::max(first, ncell_ids));
    for (std::size_t i = first; i < own; ++i)
      out[i - first] = T(mesh.cells[i]);
    if (flipped && own > first) {
      const std::size_t n_vc = std::size_t(nvc);
      for (std::size_t c = first / n_vc; c <= (own - 1) / n_vc; ++c)
        if (flipped[c])
          for (std::size_t k = 0; k < 2; ++k) {
            const std::size_t i = c * n_vc + k;
            if (i >= first && i < own)
              out[i - first] = T(mesh.cells[c * n_vc + 1 - k]);
          }
    }
    for (std::size_t i = own; i < end; ++i)
      out[i - first] = T(entity_conn[i - ncell_ids]);
  };
  auto connectivity = [&](auto type) {
    using T = decltype(type);
    write_array<T>(w, compression, level, "connectivity", 1, ncell_ids + entity_ids,
                   Bulk{connectivity_ids});
    write_array<T>(w, compression, level, "offsets", 1, nc,
                   Bulk{[&](std::size_t first, std::size_t n, T *out) {
                     const std::size_t own = std::min(first + n, std::max(first, ncells));
                     for (std::size_t c = first; c < own; ++c)
                       out[c - first] = T((c + 1) * std::size_t(nvc));
                     for (std::size_t c = own; c < first + n; ++c)
                       out[c - first] = T(entity_offsets[c - ncells]);
                   }});
  };
  // Int32 ids and offsets when they fit (every mesh below 2^31 ids): half
  // the bytes of the largest arrays to compress and write; VTK, ParaView and
  // meshio read either.
  if (ncell_ids + entity_ids <= std::size_t(std::numeric_limits<std::int32_t>::max()) &&
      mesh.num_vertices() <= std::size_t(std::numeric_limits<std::int32_t>::max()))
    connectivity(std::int32_t());
  else
    connectivity(std::int64_t());
  const std::uint8_t type = dim == 2 ? 5 : dim == 3 ? 10 : 2; // triangle, tetra, poly-vertex
  write_array<std::uint8_t>(w, compression, level, "types", 1, nc,
                            Bulk{[&](std::size_t first, std::size_t n, std::uint8_t *out) {
                              const std::size_t own = std::min(first + n, std::max(first, ncells));
                              std::fill(out, out + (own - first), type);
                              for (std::size_t c = own; c < first + n; ++c)
                                out[c - first] = entity_types[c - ncells];
                            }});
  w.text("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
  w.close();
}

} // namespace bisect
