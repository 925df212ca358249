// Native .vtu reader (see vtu_read.hpp). Facts of the format it relies on
// (VTK's "VTK File Formats" document and the files VTK 9.1 and meshio write):
//  - <VTKFile type="UnstructuredGrid" byte_order=... header_type=UInt32|UInt64
//    compressor=...> holds <UnstructuredGrid>, which holds optional
//    <FieldData> and one or more <Piece NumberOfPoints NumberOfCells>, each
//    with <PointData>, <CellData>, <Points> (one 3-component array) and
//    <Cells> (connectivity, offsets = end offset of each cell, types).
//  - A binary array starts with a header of header_type words: without a
//    compressor one word, the byte count; with one, [blocks, block size,
//    last block size (0: full), compressed size of each block], then the
//    compressed blocks, each decompressing on its own.
//  - Inline binary is base64; VTK encodes the header and the data as two
//    base64 texts one after the other, meshio as one. Reading the base64 as
//    one stream of groups where '=' padding ends a group handles both.
//  - Appended data follows the '_' after <AppendedData>; an array's offset
//    counts bytes (raw) or base64 characters from just after the '_'.
//
// Every size the file claims is checked against the bytes that are there
// before anything is allocated for it; decompressed sizes are bounded by the
// compressor's largest possible expansion of the compressed bytes present.
#include "io/vtu_read.hpp"

#include "io/file_bytes.hpp"

#include "bisect/mesh.hpp"
#include "bisect/threads.hpp"

#include <libdeflate.h>
#include <lz4.h>
#include <lzma.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace bisect::vtu {
namespace {

static_assert(std::endian::native == std::endian::little ||
              std::endian::native == std::endian::big);

std::string str(std::uint64_t v) {
  return std::to_string(v);
}

// A token of the file quoted for a message: at most 24 characters, no
// control characters (the message stays one line).
std::string quoted(std::string_view t) {
  std::string out = "'";
  for (char c : t.substr(0, 24))
    out += static_cast<unsigned char>(c) < 32 || c == 127 ? '?' : c;
  return out + (t.size() > 24 ? "...'" : "'");
}

bool is_space(char c) {
  return c == ' ' || c == '\n' || c == '\r' || c == '\t';
}

// ---------------------------------------------------------------------------
// The XML subset: elements, attributes (quoted with ' or ", the predefined
// and numeric entities decoded), character data, comments, <?...?>,
// <!DOCTYPE...> and CDATA. Parsing stops at <AppendedData>: what follows
// its '_' is data, not XML (as in VTK).

struct Attribute {
  std::string_view name;
  std::string value;
};

struct Element {
  std::string_view name;
  std::vector<Attribute> attributes;
  std::vector<std::size_t> children;  // indices into Document::elements
  std::vector<std::string_view> text; // character data directly inside, in order
  std::size_t at = 0;                 // byte offset of the '<'

  const std::string *attribute(std::string_view n) const {
    for (const auto &a : attributes)
      if (a.name == n)
        return &a.value;
    return nullptr;
  }
};

struct Document {
  std::vector<Element> elements;        // [0] is the root
  const char *appended_begin = nullptr; // just after the '_'; null without AppendedData
  const char *appended_end = nullptr;
  bool appended_base64 = false;
};

class XmlParser {
public:
  XmlParser(const std::string &path, const char *s, std::size_t n) : path_(path), s_(s), n_(n) {}

  Document parse() {
    std::size_t i = n_ >= 3 && std::memcmp(s_, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0; // UTF-8 BOM
    while (i < n_) {
      const char *lt = static_cast<const char *>(std::memchr(s_ + i, '<', n_ - i));
      const std::size_t j = lt ? std::size_t(lt - s_) : n_;
      if (j > i)
        add_text(i, std::string_view(s_ + i, j - i));
      if (!lt)
        break;
      i = j;
      if (starts(i, "<?")) {
        i = skip_past(i, "?>", "a <?...?> declaration");
      } else if (starts(i, "<!--")) {
        i = skip_past(i, "-->", "a comment");
      } else if (starts(i, "<![CDATA[")) {
        const std::size_t end = skip_past(i, "]]>", "a CDATA section");
        add_text(i, std::string_view(s_ + i + 9, end - 3 - (i + 9)));
        i = end;
      } else if (starts(i, "<!")) {
        i = skip_past(i, ">", "a <!...> declaration");
      } else if (starts(i, "</")) {
        i = end_tag(i);
      } else {
        i = start_tag(i);
        if (doc_.appended_begin)
          return std::move(doc_);
      }
    }
    if (!open_.empty())
      fail(n_, "the file ends inside <" + std::string(doc_.elements[open_.back()].name) +
                   "> (truncated?)");
    if (doc_.elements.empty())
      fail(0, "no XML element");
    return std::move(doc_);
  }

private:
  [[noreturn]] void fail(std::size_t at, const std::string &what) const {
    throw InputError(path_, "XML error at byte " + str(at) + ": " + what);
  }

  bool starts(std::size_t i, std::string_view t) const {
    return n_ - i >= t.size() && std::memcmp(s_ + i, t.data(), t.size()) == 0;
  }

  std::size_t skip_past(std::size_t i, std::string_view end, const char *what) const {
    const std::string_view rest(s_ + i, n_ - i);
    const std::size_t k = rest.find(end, 2);
    if (k == std::string_view::npos)
      fail(i, std::string("the file ends inside ") + what);
    return i + k + end.size();
  }

  void add_text(std::size_t at, std::string_view t) {
    if (!open_.empty()) {
      doc_.elements[open_.back()].text.push_back(t);
      return;
    }
    for (std::size_t k = 0; k < t.size(); ++k)
      if (!is_space(t[k]))
        fail(at + k, "text outside the root element (not an XML file?)");
  }

  std::size_t name_end(std::size_t i) const {
    while (i < n_ && !is_space(s_[i]) && s_[i] != '>' && s_[i] != '/' && s_[i] != '=' &&
           s_[i] != '<')
      ++i;
    return i;
  }

  std::size_t skip_space(std::size_t i) const {
    while (i < n_ && is_space(s_[i]))
      ++i;
    return i;
  }

  std::size_t end_tag(std::size_t i) {
    const std::size_t b = i + 2, e = name_end(b);
    const std::string_view name(s_ + b, e - b);
    const std::size_t k = skip_space(e);
    if (k >= n_)
      fail(i, "the file ends inside the end tag </" + std::string(name) + ">");
    if (s_[k] != '>')
      fail(k, "'>' expected after </" + std::string(name));
    if (open_.empty() || doc_.elements[open_.back()].name != name)
      fail(i, "</" + std::string(name) + "> does not close " +
                  (open_.empty() ? std::string("any element")
                                 : "<" + std::string(doc_.elements[open_.back()].name) + ">"));
    open_.pop_back();
    return k + 1;
  }

  std::string decode_entities(std::size_t at, std::string_view raw) const {
    std::string out;
    out.reserve(raw.size());
    for (std::size_t k = 0; k < raw.size(); ++k) {
      if (raw[k] != '&') {
        out += raw[k];
        continue;
      }
      const std::size_t semi = raw.find(';', k);
      if (semi == std::string_view::npos)
        fail(at, "'&' without ';' in an attribute value");
      const std::string_view ent = raw.substr(k + 1, semi - k - 1);
      if (ent == "lt")
        out += '<';
      else if (ent == "gt")
        out += '>';
      else if (ent == "amp")
        out += '&';
      else if (ent == "quot")
        out += '"';
      else if (ent == "apos")
        out += '\'';
      else if (ent.size() > 1 && ent[0] == '#') {
        const bool hex = ent[1] == 'x';
        unsigned code = 0;
        const char *b = ent.data() + (hex ? 2 : 1), *e = ent.data() + ent.size();
        auto r = std::from_chars(b, e, code, hex ? 16 : 10);
        if (b == e || r.ec != std::errc() || r.ptr != e || code == 0 || code > 0x10FFFF)
          fail(at, "bad character reference &" + std::string(ent) + ";");
        // UTF-8
        if (code < 0x80) {
          out += char(code);
        } else if (code < 0x800) {
          out += char(0xC0 | code >> 6), out += char(0x80 | (code & 0x3F));
        } else if (code < 0x10000) {
          out += char(0xE0 | code >> 12), out += char(0x80 | (code >> 6 & 0x3F));
          out += char(0x80 | (code & 0x3F));
        } else {
          out += char(0xF0 | code >> 18), out += char(0x80 | (code >> 12 & 0x3F));
          out += char(0x80 | (code >> 6 & 0x3F)), out += char(0x80 | (code & 0x3F));
        }
      } else {
        fail(at, "unknown entity &" + std::string(ent) + ";");
      }
      k = semi;
    }
    return out;
  }

  std::size_t start_tag(std::size_t i) {
    const std::size_t b = i + 1, e = name_end(b);
    if (e == b)
      fail(i, "'<' not followed by an element name");
    Element el;
    el.name = std::string_view(s_ + b, e - b);
    el.at = i;
    std::size_t k = e;
    bool empty = false;
    for (;;) {
      k = skip_space(k);
      if (k >= n_)
        fail(i, "the file ends inside the tag <" + std::string(el.name) + ">");
      if (s_[k] == '>') {
        ++k;
        break;
      }
      if (s_[k] == '/') {
        if (k + 1 >= n_ || s_[k + 1] != '>')
          fail(k, "'/' not followed by '>' in <" + std::string(el.name) + ">");
        k += 2;
        empty = true;
        break;
      }
      const std::size_t ne = name_end(k);
      if (ne == k)
        fail(k, "unexpected " + quoted(std::string_view(s_ + k, 1)) + " in <" +
                    std::string(el.name) + ">");
      const std::string_view name(s_ + k, ne - k);
      k = skip_space(ne);
      if (k >= n_ || s_[k] != '=')
        fail(k, "'=' expected after attribute " + std::string(name));
      k = skip_space(k + 1);
      if (k >= n_ || (s_[k] != '"' && s_[k] != '\''))
        fail(k, "quoted value expected for attribute " + std::string(name));
      const char *close = static_cast<const char *>(std::memchr(s_ + k + 1, s_[k], n_ - k - 1));
      if (!close)
        fail(k, "the file ends inside the value of attribute " + std::string(name));
      const std::size_t ve = std::size_t(close - s_);
      // VTK's elements have a handful of attributes; the limit keeps the
      // check for repeated ones cheap on hostile input.
      if (el.attributes.size() == 256)
        fail(k, "more than 256 attributes in <" + std::string(el.name) + ">");
      if (el.attribute(name))
        fail(k, "attribute " + std::string(name) + " given twice");
      el.attributes.push_back({name, decode_entities(k, std::string_view(s_ + k + 1, ve - k - 1))});
      k = ve + 1;
    }
    const std::size_t index = doc_.elements.size();
    if (open_.empty()) {
      if (!doc_.elements.empty())
        fail(i, "a second root element <" + std::string(el.name) + ">");
    } else {
      doc_.elements[open_.back()].children.push_back(index);
    }
    const bool appended = el.name == "AppendedData" && !empty;
    doc_.elements.push_back(std::move(el));
    if (appended)
      return start_appended(index, k);
    if (!empty)
      open_.push_back(index);
    return k;
  }

  std::size_t start_appended(std::size_t index, std::size_t k) {
    const Element &el = doc_.elements[index];
    const std::string *enc = el.attribute("encoding");
    if (!enc || *enc == "raw")
      doc_.appended_base64 = false;
    else if (*enc == "base64")
      doc_.appended_base64 = true;
    else
      fail(el.at, "AppendedData encoding " + quoted(*enc) + " is not raw or base64");
    k = skip_space(k);
    if (k >= n_ || s_[k] != '_')
      fail(k, "AppendedData does not start with '_'");
    doc_.appended_begin = s_ + k + 1;
    // The data ends at </AppendedData> when the file still has it (looked
    // for near the end only: raw data may hold anything).
    const std::string_view tail_marker = "</AppendedData>";
    const std::size_t from = std::max(k + 1, n_ > 4096 ? n_ - 4096 : std::size_t(0));
    const std::string_view tail(s_ + from, n_ - from);
    const std::size_t t = tail.rfind(tail_marker);
    doc_.appended_end = t == std::string_view::npos ? s_ + n_ : s_ + from + t;
    return n_;
  }

  const std::string &path_;
  const char *s_;
  std::size_t n_;
  Document doc_;
  std::vector<std::size_t> open_;
};

// ---------------------------------------------------------------------------
// Value types.

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

struct ScalarInfo {
  std::string_view name;
  Scalar type;
  int size;
  bool integer;
};

constexpr std::array<ScalarInfo, 10> kScalars = {{
    {"Int8", Scalar::Int8, 1, true},
    {"UInt8", Scalar::UInt8, 1, true},
    {"Int16", Scalar::Int16, 2, true},
    {"UInt16", Scalar::UInt16, 2, true},
    {"Int32", Scalar::Int32, 4, true},
    {"UInt32", Scalar::UInt32, 4, true},
    {"Int64", Scalar::Int64, 8, true},
    {"UInt64", Scalar::UInt64, 8, true},
    {"Float32", Scalar::Float32, 4, false},
    {"Float64", Scalar::Float64, 8, false},
}};

const ScalarInfo &info(Scalar t) {
  return kScalars[std::size_t(t)];
}

// The range of an integer type, as int64 (UInt64's top is checked apart).
std::pair<std::int64_t, std::int64_t> int_range(Scalar t) {
  switch (t) {
  case Scalar::Int8:
    return {INT8_MIN, INT8_MAX};
  case Scalar::UInt8:
    return {0, UINT8_MAX};
  case Scalar::Int16:
    return {INT16_MIN, INT16_MAX};
  case Scalar::UInt16:
    return {0, UINT16_MAX};
  case Scalar::Int32:
    return {INT32_MIN, INT32_MAX};
  case Scalar::UInt32:
    return {0, UINT32_MAX};
  default:
    return {INT64_MIN, INT64_MAX};
  }
}

enum class Compressor { None, Zlib, Lz4, Lzma };

// The most a compressed byte can expand to (deflate: 1032; LZ4: 255; LZMA2
// about 7000 on long runs), with room to spare; anything claiming more is
// corrupt and is refused before any allocation.
std::uint64_t max_expansion(Compressor c) {
  switch (c) {
  case Compressor::Zlib:
    return 1100;
  case Compressor::Lz4:
    return 260;
  case Compressor::Lzma:
    return 8192;
  default:
    return 1;
  }
}

// ---------------------------------------------------------------------------
// One DataArray element, as declared.

enum class Format { Ascii, Binary, Appended };

struct ArraySpec {
  std::string label; // for messages: "point data array 'temperature'"
  std::string name;
  bool numeric = true;
  Scalar type = Scalar::Float64;
  int components = 1;
  Format format = Format::Ascii;
  std::uint64_t offset = 0;            // appended
  std::optional<std::uint64_t> tuples; // NumberOfTuples, when given
  const Element *element = nullptr;
};

constexpr std::uint64_t kAnyCount = std::numeric_limits<std::uint64_t>::max();

// ---------------------------------------------------------------------------
// Base64 as a stream of bytes.

constexpr signed char kPad = -3, kSpace = -2, kBad = -1;

constexpr std::array<signed char, 256> make_base64_table() {
  std::array<signed char, 256> t{};
  for (auto &v : t)
    v = kBad;
  for (int c = 'A'; c <= 'Z'; ++c)
    t[c] = static_cast<signed char>(c - 'A');
  for (int c = 'a'; c <= 'z'; ++c)
    t[c] = static_cast<signed char>(c - 'a' + 26);
  for (int c = '0'; c <= '9'; ++c)
    t[c] = static_cast<signed char>(c - '0' + 52);
  t['+'] = 62;
  t['/'] = 63;
  t['='] = kPad;
  t[' '] = t['\n'] = t['\r'] = t['\t'] = kSpace;
  return t;
}
constexpr auto kBase64 = make_base64_table();

class Base64 {
public:
  Base64(const char *p, const char *end) : p_(p), end_(end) {}

  // At most this many bytes are left.
  std::uint64_t max_left() const { return std::uint64_t(end_ - p_) / 4 * 3 + 3 + (have_ - next_); }

  // Reads n bytes; false when the text ends first or holds a character that
  // is not base64 (bad_at() then points at it).
  bool read(unsigned char *out, std::size_t n) {
    while (n && next_ < have_)
      *out++ = buf_[next_++], --n;
    // Whole groups straight into the output.
    const auto *u = reinterpret_cast<const unsigned char *>(p_);
    const auto *ue = reinterpret_cast<const unsigned char *>(end_);
    while (n >= 3 && ue - u >= 4) {
      const int a = kBase64[u[0]], b = kBase64[u[1]], c = kBase64[u[2]], d = kBase64[u[3]];
      if ((a | b | c | d) < 0)
        break;
      out[0] = static_cast<unsigned char>(a << 2 | b >> 4);
      out[1] = static_cast<unsigned char>(b << 4 | c >> 2);
      out[2] = static_cast<unsigned char>(c << 6 | d);
      out += 3, n -= 3, u += 4;
    }
    p_ = reinterpret_cast<const char *>(u);
    while (n) {
      if (!group())
        return false;
      while (n && next_ < have_)
        *out++ = buf_[next_++], --n;
    }
    return true;
  }

  const char *bad_at() const { return bad_; }

private:
  // Decodes the next group of four characters (whitespace skipped; '='
  // padding or the end of the text may shorten it) into buf_.
  bool group() {
    int v[4], k = 0, pads = 0;
    while (k < 4 && p_ < end_) {
      const signed char c = kBase64[static_cast<unsigned char>(*p_)];
      if (c == kSpace) {
        ++p_;
        continue;
      }
      if (c == kBad || (c != kPad && pads) || (c == kPad && k < 2)) {
        bad_ = p_;
        return false;
      }
      if (c == kPad)
        ++pads;
      v[k++] = c == kPad ? 0 : c;
      ++p_;
    }
    if (k < 2) { // nothing, or one lone character
      if (k == 1)
        bad_ = p_ - 1;
      return false;
    }
    for (int j = k; j < 4; ++j)
      v[j] = 0, ++pads; // unpadded end of text
    buf_[0] = static_cast<unsigned char>(v[0] << 2 | v[1] >> 4);
    buf_[1] = static_cast<unsigned char>(v[1] << 4 | v[2] >> 2);
    buf_[2] = static_cast<unsigned char>(v[2] << 6 | v[3]);
    have_ = 3 - pads;
    next_ = 0;
    return have_ > 0;
  }

  const char *p_, *end_;
  const char *bad_ = nullptr;
  unsigned char buf_[3] = {0, 0, 0};
  int have_ = 0, next_ = 0;
};

// ---------------------------------------------------------------------------
// Reading one array.

struct FileFormat {
  bool swap = false;    // byte_order differs from this machine's
  int header_bytes = 4; // header_type UInt32 or UInt64
  Compressor compressor = Compressor::None;
};

// The first point id of an array that is no point id at all (negative, or
// past 32 bits): such ids are stored as kBadId and reported by the cell
// check, which knows the cell, with this text.
constexpr std::uint32_t kBadId = kNoVertex;
struct BadIds {
  bool any = false;
  std::string first;
};

// The encoded bytes of one binary array: a span of the file (raw appended)
// or base64 text (inline, or base64 appended).
class ByteSource {
public:
  ByteSource(const std::string &path, const ArraySpec &a, BadIds *bad, const char *raw,
             const char *end)
      : path_(path), a_(a), bad_(bad), raw_(true), p_(raw), end_(end), b64_(nullptr, nullptr) {}
  ByteSource(const std::string &path, const ArraySpec &a, BadIds *bad, Base64 b64)
      : path_(path), a_(a), bad_(bad), raw_(false), b64_(b64) {}

  const std::string &path() const { return path_; }
  const std::string &label() const { return a_.label; }
  BadIds *bad_ids() const { return bad_; }

  std::uint64_t max_left() const { return raw_ ? std::uint64_t(end_ - p_) : b64_.max_left(); }

  void read(void *out, std::size_t n, const char *what) {
    if (raw_) {
      if (std::uint64_t(end_ - p_) < n)
        fail(std::string(what) + " runs past the end of the file");
      std::memcpy(out, p_, n);
      p_ += n;
      return;
    }
    if (!b64_.read(static_cast<unsigned char *>(out), n)) {
      if (b64_.bad_at())
        fail(std::string("base64 text of the ") + what + " holds " + quoted({b64_.bad_at(), 1}));
      fail(std::string(what) + " runs past the end of its base64 text");
    }
  }

  // n contiguous bytes: the file itself when raw, else decoded into scratch
  // (which only grows, so that one buffer serves all arrays).
  const unsigned char *view(std::size_t n, std::vector<unsigned char> &scratch, const char *what) {
    if (raw_) {
      if (std::uint64_t(end_ - p_) < n)
        fail(std::string(what) + " runs past the end of the file");
      const auto *v = reinterpret_cast<const unsigned char *>(p_);
      p_ += n;
      return v;
    }
    if (scratch.size() < n)
      scratch.resize(n);
    read(scratch.data(), n, what);
    return scratch.data();
  }

  std::uint64_t word(int bytes, bool swap) {
    unsigned char b[8];
    read(b, std::size_t(bytes), "header");
    if (swap)
      std::reverse(b, b + bytes);
    if (bytes == 4) {
      std::uint32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    std::uint64_t v;
    std::memcpy(&v, b, 8);
    return v;
  }

  [[noreturn]] void fail(const std::string &what) const {
    throw InputError(path_, a_.label + ": " + what);
  }

private:
  const std::string &path_;
  const ArraySpec &a_;
  BadIds *bad_;
  bool raw_;
  const char *p_ = nullptr, *end_ = nullptr;
  Base64 b64_;
};

struct FreeDecompressor {
  void operator()(libdeflate_decompressor *d) const { libdeflate_free_decompressor(d); }
};

void decompress_block(ByteSource &src, Compressor c, const unsigned char *in, std::size_t in_size,
                      unsigned char *out, std::size_t out_size, std::uint64_t block) {
  const std::string which = "block " + str(block);
  switch (c) {
  case Compressor::Zlib: {
    // libdeflate (whole blocks, which VTK writes): 0.44 s of CPU where zlib
    // took 0.75 on a 5.4M-tet file.
    thread_local const std::unique_ptr<libdeflate_decompressor, FreeDecompressor> inflater(
        libdeflate_alloc_decompressor());
    if (!inflater)
      throw std::bad_alloc();
    std::size_t got = 0;
    const libdeflate_result rc =
        libdeflate_zlib_decompress(inflater.get(), in, in_size, out, out_size, &got);
    if (rc == LIBDEFLATE_INSUFFICIENT_SPACE)
      src.fail("zlib " + which + " holds more than the " + str(out_size) +
               " bytes its header says");
    if (rc != LIBDEFLATE_SUCCESS)
      src.fail("zlib " + which + " is corrupt");
    if (got != out_size)
      src.fail("zlib " + which + " holds " + str(got) + " bytes, its header says " + str(out_size));
    return;
  }
  case Compressor::Lz4: {
    if (in_size > std::size_t(LZ4_MAX_INPUT_SIZE) || out_size > std::size_t(INT32_MAX))
      src.fail("lz4 " + which + " is larger than LZ4 allows");
    const int got = LZ4_decompress_safe(reinterpret_cast<const char *>(in),
                                        reinterpret_cast<char *>(out), int(in_size), int(out_size));
    if (got < 0)
      src.fail("lz4 " + which + " is corrupt (or larger than its header says)");
    if (std::size_t(got) != out_size)
      src.fail("lz4 " + which + " holds " + str(std::uint64_t(got)) + " bytes, its header says " +
               str(out_size));
    return;
  }
  case Compressor::Lzma: {
    // The memory limit caps the dictionary a corrupt stream header may ask for.
    std::uint64_t memlimit = std::uint64_t(256) << 20;
    std::size_t in_pos = 0, out_pos = 0;
    const lzma_ret rc = lzma_stream_buffer_decode(&memlimit, 0, nullptr, in, &in_pos, in_size, out,
                                                  &out_pos, out_size);
    if (rc == LZMA_BUF_ERROR && out_pos == out_size)
      src.fail("lzma " + which + " holds more than the " + str(out_size) +
               " bytes its header says (or is corrupt)");
    if (rc != LZMA_OK)
      src.fail("lzma " + which + " is corrupt (liblzma error " + std::to_string(int(rc)) + ")");
    if (out_pos != out_size)
      src.fail("lzma " + which + " holds " + str(out_pos) + " bytes, its header says " +
               str(out_size));
    return;
  }
  default:
    src.fail("internal: no compressor");
  }
}

// The payload of a binary array: its size from the header, then its bytes.
class BinaryPayload {
public:
  BinaryPayload(ByteSource &src, const FileFormat &f) : src_(src), f_(f) {
    const int w = f.header_bytes;
    if (f.compressor == Compressor::None) {
      size_ = src.word(w, f.swap);
      if (size_ > src.max_left())
        src.fail("header claims " + str(size_) + " bytes, but at most " + str(src.max_left()) +
                 " are left in the file");
      return;
    }
    const std::uint64_t blocks = src.word(w, f.swap);
    block_ = src.word(w, f.swap);
    last_ = src.word(w, f.swap);
    if (blocks > src.max_left() / std::uint64_t(w))
      src.fail("compression header claims " + str(blocks) + " blocks, more than the file holds");
    sizes_.resize(blocks);
    std::uint64_t compressed = 0;
    for (std::size_t b = 0; b < sizes_.size(); ++b) {
      sizes_[b] = src.word(w, f.swap);
      if (sizes_[b] > src.max_left())
        src.fail("compression header: block " + str(b) + " (" + str(sizes_[b]) +
                 " bytes) runs past the end of the data");
      compressed += sizes_[b]; // each term is below the file size: no overflow
    }
    if (compressed > src.max_left())
      src.fail("compression header: the blocks (" + str(compressed) +
               " bytes) run past the end of the file");
    if (blocks == 0) {
      size_ = 0;
      return;
    }
    if (block_ == 0)
      src.fail("compression header: block size 0");
    if (last_ > block_)
      src.fail("compression header: last block (" + str(last_) + " bytes) larger than a block (" +
               str(block_) + ")");
    const std::uint64_t full = blocks - (last_ ? 1 : 0);
    const std::uint64_t ratio = max_expansion(f.compressor);
    if (block_ > (std::uint64_t(1) << 40) || full > (std::uint64_t(1) << 40) / block_ ||
        full * block_ + last_ > compressed * ratio + (std::uint64_t(1) << 16))
      src.fail("compression header: " + str(blocks) + " blocks of " + str(block_) +
               " bytes are out of proportion to the " + str(compressed) + " compressed bytes");
    size_ = full * block_ + last_;
    compressed_ = compressed;
  }

  std::uint64_t size() const { return size_; }

  // Hands the decoded bytes to put(bytes, n) in order, a block (or a
  // chunk of base64) at a time: the buffers stay small and are reused, as
  // fresh memory costs a page fault per page.
  template <class Put>
  void fill(Put &&put, std::vector<unsigned char> &in_buf, std::vector<unsigned char> &out_buf) {
    if (f_.compressor == Compressor::None) {
      constexpr std::uint64_t kChunk = 3 << 16;
      for (std::uint64_t done = 0; done < size_;) {
        const std::size_t n = std::size_t(std::min(kChunk, size_ - done));
        put(src_.view(n, in_buf, "data"), n);
        done += n;
      }
      return;
    }
    const std::uint64_t ratio = max_expansion(f_.compressor);
    for (std::size_t b = 0; b < sizes_.size(); ++b) {
      const std::uint64_t n = b + 1 == sizes_.size() && last_ ? last_ : block_;
      if (n > sizes_[b] * ratio + (std::uint64_t(1) << 16))
        src_.fail("compression header: block " + str(b) + " of " + str(sizes_[b]) +
                  " bytes cannot hold " + str(n) + " bytes");
      const unsigned char *in = src_.view(std::size_t(sizes_[b]), in_buf, "compressed data");
      if (out_buf.size() < n)
        out_buf.resize(std::size_t(n));
      decompress_block(src_, f_.compressor, in, std::size_t(sizes_[b]), out_buf.data(),
                       std::size_t(n), b);
      put(out_buf.data(), std::size_t(n));
    }
  }

private:
  ByteSource &src_;
  const FileFormat &f_;
  std::uint64_t size_ = 0, block_ = 0, last_ = 0, compressed_ = 0;
  std::vector<std::uint64_t> sizes_;
};

// What an integer of the file becomes in an array of D: doubles (data),
// int64 (offsets), uint32 (point ids: at most kBadId, see BadIds), uint8
// (cell types: a type past 255 is an error here).
template <class D, class V>
D narrow(V v, std::uint64_t index, const std::string &label, const std::string &path, BadIds *bad) {
  if constexpr (std::is_same_v<D, double>) {
    return static_cast<double>(v);
  } else if constexpr (std::is_same_v<D, std::int64_t>) {
    if constexpr (std::is_same_v<V, std::uint64_t>)
      if (v > std::uint64_t(INT64_MAX))
        throw InputError(path, label + ": value " + str(index) + " (" + std::to_string(v) +
                                   ") is out of range");
    return static_cast<std::int64_t>(v);
  } else if constexpr (std::is_same_v<D, std::uint32_t>) {
    bool ok = true;
    if constexpr (std::is_signed_v<V>)
      ok = v >= 0;
    if (ok && std::uint64_t(v) < kBadId)
      return static_cast<std::uint32_t>(v);
    if (bad && !bad->any)
      bad->any = true, bad->first = std::to_string(v);
    return kBadId;
  } else if constexpr (!std::is_same_v<D, std::uint8_t>) {
    // A StoredState array in its file's type (D is that type: the value fits).
    static_assert(std::is_same_v<D, std::int8_t> || std::is_same_v<D, std::int16_t> ||
                  std::is_same_v<D, std::uint16_t> || std::is_same_v<D, std::int32_t>);
    if (!std::in_range<D>(v))
      throw InputError(path, label + ": value " + str(index) + " is out of range");
    return static_cast<D>(v);
  } else {
    bool ok = std::uint64_t(v) <= 255;
    if constexpr (std::is_signed_v<V>)
      ok = v >= 0 && v <= 255;
    if (!ok)
      throw InputError(path, label + ": cell " + str(index) + " has VTK type " + std::to_string(v) +
                                 ", which is not a known linear cell type");
    return static_cast<std::uint8_t>(v);
  }
}

template <class T> T load(const unsigned char *p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap)
    std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

// Converts n values of type S at `src` into `out` (value `first` of the
// array onwards; see narrow).
template <class D, class S>
void convert_from(const unsigned char *src, std::size_t n, bool swap, D *out, std::size_t first,
                  const ByteSource &f) {
  if constexpr (std::is_same_v<D, S>) {
    if (!swap) {
      std::memcpy(out, src, n * sizeof(S));
      return;
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    out[i] =
        narrow<D>(load<S>(src + i * sizeof(S), swap), first + i, f.label(), f.path(), f.bad_ids());
}

template <class D>
void convert(Scalar t, const unsigned char *src, std::size_t n, bool swap, D *out,
             std::size_t first, const ByteSource &f) {
  switch (t) {
  case Scalar::Int8:
    return convert_from<D, std::int8_t>(src, n, swap, out, first, f);
  case Scalar::UInt8:
    return convert_from<D, std::uint8_t>(src, n, swap, out, first, f);
  case Scalar::Int16:
    return convert_from<D, std::int16_t>(src, n, swap, out, first, f);
  case Scalar::UInt16:
    return convert_from<D, std::uint16_t>(src, n, swap, out, first, f);
  case Scalar::Int32:
    return convert_from<D, std::int32_t>(src, n, swap, out, first, f);
  case Scalar::UInt32:
    return convert_from<D, std::uint32_t>(src, n, swap, out, first, f);
  case Scalar::Int64:
    return convert_from<D, std::int64_t>(src, n, swap, out, first, f);
  case Scalar::UInt64:
    return convert_from<D, std::uint64_t>(src, n, swap, out, first, f);
  case Scalar::Float32:
    if constexpr (std::is_same_v<D, double>)
      return convert_from<D, float>(src, n, swap, out, first, f);
    break;
  case Scalar::Float64:
    if constexpr (std::is_same_v<D, double>)
      return convert_from<D, double>(src, n, swap, out, first, f);
    break;
  }
  f.fail("internal: float data for an integer array");
}

// Converts bytes handed over in pieces of any length (a value may straddle
// two pieces) into out[0, n).
template <class D> class Converter {
public:
  Converter(Scalar t, bool swap, D *out, const ByteSource &f)
      : t_(t), size_(std::size_t(info(t).size)), swap_(swap), out_(out), f_(f) {}

  void operator()(const unsigned char *p, std::size_t n) {
    if (carried_) {
      const std::size_t take = std::min(n, size_ - carried_);
      std::memcpy(carry_ + carried_, p, take);
      carried_ += take, p += take, n -= take;
      if (carried_ < size_)
        return;
      convert<D>(t_, carry_, 1, swap_, out_ + done_, done_, f_);
      ++done_, carried_ = 0;
    }
    const std::size_t whole = n / size_;
    convert<D>(t_, p, whole, swap_, out_ + done_, done_, f_);
    done_ += whole;
    carried_ = n - whole * size_;
    std::memcpy(carry_, p + whole * size_, carried_);
  }

private:
  Scalar t_;
  std::size_t size_;
  bool swap_;
  D *out_;
  const ByteSource &f_;
  std::size_t done_ = 0, carried_ = 0;
  unsigned char carry_[8] = {};
};

// ASCII values: tokens separated by whitespace; each must be a number of
// the array's type (an integer in range for integer types).
template <class D>
std::vector<D> parse_ascii(const std::string &path, const ArraySpec &a, std::uint64_t expected,
                           BadIds *bad_ids) {
  auto fail = [&](const std::string &what) -> void {
    throw InputError(path, a.label + ": " + what);
  };
  std::size_t chars = 0;
  for (auto t : a.element->text)
    chars += t.size();
  std::vector<D> out;
  out.reserve(std::size_t(std::min<std::uint64_t>(expected, chars / 2 + 1)));
  const ScalarInfo &ti = info(a.type);
  std::uint64_t index = 0;
  for (std::string_view text : a.element->text) {
    const char *p = text.data(), *end = p + text.size();
    for (;;) {
      while (p < end && is_space(*p))
        ++p;
      if (p == end)
        break;
      const char *tok = p;
      while (p < end && !is_space(*p))
        ++p;
      const std::string_view token(tok, std::size_t(p - tok));
      if (index == expected)
        fail("has more than the " + str(expected) + " values expected");
      const char *b = tok + (tok[0] == '+' && p - tok > 1 && tok[1] != '-' ? 1 : 0);
      auto bad = [&](const char *why) {
        fail("value " + str(index) + " (" + quoted(token) + ") is " + why + " " +
             std::string(ti.name));
      };
      D value{};
      if (!ti.integer) {
        double v = 0;
        std::from_chars_result r;
        if (a.type == Scalar::Float32) {
          float f = 0;
          r = std::from_chars(b, p, f);
          v = f;
        } else {
          r = std::from_chars(b, p, v);
        }
        if (r.ptr != p || (r.ec != std::errc() && r.ec != std::errc::result_out_of_range))
          bad("not a number of type");
        if (r.ec == std::errc::result_out_of_range) {
          // Underflow to a subnormal or zero is a value; overflow is not.
          const std::string copy(b, p);
          v = a.type == Scalar::Float32 ? double(std::strtof(copy.c_str(), nullptr))
                                        : std::strtod(copy.c_str(), nullptr);
          if (std::isinf(v))
            bad("out of range for");
        }
        if constexpr (std::is_same_v<D, double>) // integer targets take integer arrays only
          value = v;
      } else if (a.type == Scalar::UInt64) {
        std::uint64_t v = 0;
        const auto r = std::from_chars(b, p, v);
        if (r.ptr != p || r.ec == std::errc::invalid_argument)
          bad("not an integer of type");
        if (r.ec != std::errc())
          bad("out of range for");
        value = narrow<D>(v, index, a.label, path, bad_ids);
      } else {
        std::int64_t v = 0;
        const auto r = std::from_chars(b, p, v);
        if (r.ptr != p || r.ec == std::errc::invalid_argument)
          bad("not an integer of type");
        const auto [lo, hi] = int_range(a.type);
        if (r.ec != std::errc() || v < lo || v > hi)
          bad("out of range for");
        value = narrow<D>(v, index, a.label, path, bad_ids);
      }
      out.push_back(value);
      ++index;
    }
  }
  if (expected != kAnyCount && index != expected)
    fail("has " + str(index) + " values, expected " + str(expected));
  return out;
}

// The character data of a binary DataArray: its one non-blank text piece
// (child elements such as InformationKey may split it).
std::string_view binary_text(const ArraySpec &a, std::string &joined) {
  std::string_view found;
  int pieces = 0;
  for (auto t : a.element->text)
    if (std::any_of(t.begin(), t.end(), [](char c) { return !is_space(c); })) {
      found = t;
      ++pieces;
    }
  if (pieces <= 1)
    return found;
  joined.clear();
  for (auto t : a.element->text)
    joined.append(t);
  return joined;
}

class ArrayReader {
public:
  ArrayReader(const std::string &path, const Document &doc, const FileFormat &f)
      : path_(path), doc_(doc), f_(f) {}

  // The values of `a`: `expected` of them (kAnyCount: as many as the data
  // holds, a whole number of tuples).
  template <class D>
  std::vector<D> read(const ArraySpec &a, std::uint64_t expected, BadIds *bad = nullptr) const {
    if (!std::is_same_v<D, double> && !info(a.type).integer)
      throw InputError(path_, a.label + " has type " + std::string(info(a.type).name) +
                                  ", expected an integer type");
    std::vector<D> out;
    if (a.format == Format::Ascii) {
      out = parse_ascii<D>(path_, a, expected, bad);
    } else if (a.format == Format::Binary) {
      std::string joined;
      const std::string_view text = binary_text(a, joined);
      ByteSource src(path_, a, bad, Base64(text.data(), text.data() + text.size()));
      out = read_binary<D>(src, a, expected);
    } else {
      if (!doc_.appended_begin)
        throw InputError(path_, a.label + " is appended, but the file has no <AppendedData>");
      const std::uint64_t avail = std::uint64_t(doc_.appended_end - doc_.appended_begin);
      if (a.offset >= avail) // even an empty array has a header
        throw InputError(path_, a.label + ": offset " + str(a.offset) +
                                    " is past the end of the appended data (" + str(avail) +
                                    (doc_.appended_base64 ? " characters)" : " bytes)"));
      const char *at = doc_.appended_begin + a.offset;
      if (doc_.appended_base64) {
        ByteSource src(path_, a, bad, Base64(at, doc_.appended_end));
        out = read_binary<D>(src, a, expected);
      } else {
        ByteSource src(path_, a, bad, at, doc_.appended_end);
        out = read_binary<D>(src, a, expected);
      }
    }
    if (out.size() % std::size_t(a.components))
      throw InputError(path_, a.label + " has " + str(out.size()) +
                                  " values, not a multiple of its " + std::to_string(a.components) +
                                  " components");
    return out;
  }

private:
  template <class D>
  std::vector<D> read_binary(ByteSource &src, const ArraySpec &a, std::uint64_t expected) const {
    BinaryPayload payload(src, f_);
    const std::uint64_t size = info(a.type).size, bytes = payload.size();
    if (bytes % size)
      src.fail("holds " + str(bytes) + " bytes, not a whole number of " +
               std::string(info(a.type).name) + " values");
    const std::uint64_t n = bytes / size;
    if (expected != kAnyCount && n != expected)
      src.fail("holds " + str(n) + " values (" + str(bytes) + " bytes), expected " + str(expected));
    std::vector<D> out(static_cast<std::size_t>(n));
    // Block buffers (one block, or a chunk of base64, at a time), reused
    // from block to block; per call, as arrays are read in parallel.
    std::vector<unsigned char> in_buf, out_buf;
    payload.fill(Converter<D>(a.type, f_.swap, out.data(), src), in_buf, out_buf);
    return out;
  }

  const std::string &path_;
  const Document &doc_;
  const FileFormat &f_;
};

// The reading of a piece's arrays as steps run in parallel (each array is
// decoded on its own), reported as if run one after the other: the first
// step in that order that failed throws its error. plan() adds the steps
// (its code may fail too, which ends the plan there); run() runs them all,
// with `between(i)` called in order before step i's error is looked at (for
// checks that need the earlier steps' results).
class ParallelSteps {
public:
  void add(std::function<void()> step, std::uint64_t cost) {
    steps_.push_back(std::move(step));
    costs_.push_back(cost);
  }
  std::size_t size() const { return steps_.size(); }

  template <class F> void plan(F &&f) {
    try {
      f();
    } catch (...) {
      plan_error_ = std::current_exception();
      plan_error_at_ = steps_.size();
    }
  }

  template <class Between> void run(Between &&between) {
    const std::size_t n = steps_.size();
    std::vector<std::exception_ptr> errors(n);
    // Largest first, so that the last one to start is a small one.
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i)
      order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return costs_[a] > costs_[b]; });
    const int workers = int(std::clamp<std::size_t>(n, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (std::size_t k = 0; k < n; ++k) {
      try {
        steps_[order[k]]();
      } catch (...) {
        errors[order[k]] = std::current_exception();
      }
    }
    for (std::size_t i = 0; i <= n; ++i) {
      between(i);
      if (plan_error_ && plan_error_at_ == i)
        std::rethrow_exception(plan_error_);
      if (i < n && errors[i])
        std::rethrow_exception(errors[i]);
    }
  }

private:
  std::vector<std::function<void()>> steps_;
  std::vector<std::uint64_t> costs_;
  std::exception_ptr plan_error_;
  std::size_t plan_error_at_ = 0;
};

// ---------------------------------------------------------------------------
// The grid.

std::uint64_t parse_count(const std::string &path, const Element &e, const char *attr,
                          const std::string &where, std::optional<std::uint64_t> fallback) {
  const std::string *v = e.attribute(attr);
  if (!v) {
    if (fallback)
      return *fallback;
    throw InputError(path, where + " has no " + attr);
  }
  std::size_t b = 0, end = v->size();
  while (b < end && is_space((*v)[b]))
    ++b;
  while (end > b && is_space((*v)[end - 1]))
    --end;
  std::uint64_t n = 0;
  const auto r = std::from_chars(v->data() + b, v->data() + end, n);
  if (b == end || r.ec != std::errc() || r.ptr != v->data() + end)
    throw InputError(path,
                     where + ": " + attr + " " + quoted(*v) + " is not a non-negative integer");
  return n;
}

class GridReader {
public:
  GridReader(const std::string &path, const Document &doc, bool keep_state_types)
      : path_(path), doc_(doc), arrays_(path, doc, format_), keep_state_types_(keep_state_types) {}

  Grid read() {
    const Element &root = doc_.elements[0];
    if (root.name != "VTKFile")
      fail("the root element is <" + std::string(root.name) + ">, not <VTKFile>");
    read_file_attributes(root);
    const Element *grid = nullptr;
    for (std::size_t c : root.children)
      if (doc_.elements[c].name == "UnstructuredGrid") {
        grid = &doc_.elements[c];
        break;
      }
    if (!grid)
      fail("no <UnstructuredGrid> element");
    Grid g;
    std::vector<const Element *> pieces;
    for (std::size_t c : grid->children) {
      const Element &e = doc_.elements[c];
      if (e.name == "Piece")
        pieces.push_back(&e);
      else if (e.name == "FieldData")
        g.field_data = read_field_data(e);
    }
    if (pieces.empty())
      fail("<UnstructuredGrid> has no <Piece>");
    // (Pieces are appended as doubles: the stored form only for one piece.)
    keep_state_types_ = keep_state_types_ && pieces.size() == 1;
    for (std::size_t p = 0; p < pieces.size(); ++p)
      read_piece(g, *pieces[p], p, pieces.size());
    return g;
  }

private:
  [[noreturn]] void fail(const std::string &what) const { throw InputError(path_, what); }

  void read_file_attributes(const Element &root) {
    const std::string *type = root.attribute("type");
    if (!type || *type != "UnstructuredGrid")
      fail("VTKFile type is " + (type ? quoted(*type) : std::string("missing")) +
           ", expected 'UnstructuredGrid'");
    if (const std::string *v = root.attribute("version")) {
      int major = 0;
      const auto r = std::from_chars(v->data(), v->data() + v->size(), major);
      if (r.ec != std::errc() || major < 0 || major > 2)
        fail("VTKFile version " + quoted(*v) + " is not one this reader knows (0.1 to 2.x)");
    }
    const std::string *order = root.attribute("byte_order");
    bool big = false;
    if (order && *order == "BigEndian")
      big = true;
    else if (order && *order != "LittleEndian")
      fail("byte_order " + quoted(*order) + " is not LittleEndian or BigEndian");
    format_.swap = big != (std::endian::native == std::endian::big);
    const std::string *header = root.attribute("header_type");
    if (!header || *header == "UInt32")
      format_.header_bytes = 4;
    else if (*header == "UInt64")
      format_.header_bytes = 8;
    else
      fail("header_type " + quoted(*header) + " is not UInt32 or UInt64");
    const std::string *comp = root.attribute("compressor");
    if (!comp || comp->empty())
      format_.compressor = Compressor::None;
    else if (*comp == "vtkZLibDataCompressor")
      format_.compressor = Compressor::Zlib;
    else if (*comp == "vtkLZ4DataCompressor")
      format_.compressor = Compressor::Lz4;
    else if (*comp == "vtkLZMADataCompressor")
      format_.compressor = Compressor::Lzma;
    else
      fail("unknown compressor " + quoted(*comp));
  }

  ArraySpec spec(const Element &e, const std::string &label) const {
    ArraySpec a;
    a.element = &e;
    a.label = label;
    if (const std::string *n = e.attribute("Name"))
      a.name = *n;
    const std::string *type = e.attribute("type");
    if (!type)
      fail(label + " has no type attribute");
    if (*type == "String" || *type == "Bit") {
      a.numeric = false;
    } else {
      auto it = std::find_if(kScalars.begin(), kScalars.end(),
                             [&](const ScalarInfo &s) { return s.name == *type; });
      if (it == kScalars.end())
        fail(label + " has unknown type " + quoted(*type));
      a.type = it->type;
    }
    const std::uint64_t comps = parse_count(path_, e, "NumberOfComponents", label, 1);
    if (comps < 1 || comps > 4096)
      fail(label + ": NumberOfComponents " + str(comps) + " is out of range");
    a.components = int(comps);
    if (e.attribute("NumberOfTuples"))
      a.tuples = parse_count(path_, e, "NumberOfTuples", label, std::nullopt);
    const std::string *format = e.attribute("format");
    if (!format || *format == "ascii")
      a.format = Format::Ascii;
    else if (*format == "binary")
      a.format = Format::Binary;
    else if (*format == "appended")
      a.format = Format::Appended;
    else
      fail(label + ": unknown format " + quoted(*format));
    if (a.format == Format::Appended && a.numeric) {
      const std::string *off = e.attribute("offset");
      if (!off)
        fail(label + " is appended but has no offset");
      if (off->empty() || (*off)[0] == '-')
        fail(label + ": offset " + quoted(*off) + " is not a non-negative integer");
      a.offset = parse_count(path_, e, "offset", label, std::nullopt);
    }
    return a;
  }

  // The DataArray children of a section, with labels "<what> array 'name'".
  std::vector<ArraySpec> specs(const Element &section, const std::string &what,
                               const std::string &piece) const {
    std::vector<ArraySpec> out;
    std::set<std::string_view> names;
    for (std::size_t c : section.children) {
      const Element &e = doc_.elements[c];
      if (e.name != "DataArray")
        continue;
      const std::string *n = e.attribute("Name");
      const std::string label =
          piece + what + " array " +
          (n && !n->empty() ? quoted(*n) : std::to_string(out.size()) + " (unnamed)");
      out.push_back(spec(e, label));
      // Two arrays of one name would be one array in VTK (the later replaces
      // the earlier): refused as ambiguous.
      if (n && !n->empty() && !names.insert(*n).second)
        fail(piece + "two " + what + " arrays named " + quoted(*n));
    }
    return out;
  }

  std::vector<Array> read_field_data(const Element &e) const {
    std::vector<Array> out;
    for (const ArraySpec &a : specs(e, "field data", "")) {
      Array arr{a.name, a.components, a.numeric, {}, std::string(info(a.type).name), false, {}};
      if (a.numeric) {
        std::uint64_t want = kAnyCount;
        if (a.tuples && *a.tuples <= kAnyCount / std::uint64_t(a.components))
          want = *a.tuples * std::uint64_t(a.components);
        arr.values = arrays_.read<double>(a, want);
      }
      out.push_back(std::move(arr));
    }
    return out;
  }

  static std::uint64_t times(std::uint64_t n, int k) {
    return n > kAnyCount / 8192 ? kAnyCount - 1 : n * std::uint64_t(k); // never kAnyCount
  }

  // Adds the reading of a section's arrays (into `out`, sized here) to `steps`.
  void plan_data(ParallelSteps &steps, const Element *section, const std::string &what,
                 const std::string &piece, std::uint64_t tuples, std::vector<Array> &out) const {
    if (!section)
      return;
    const std::vector<ArraySpec> all = specs(*section, what, piece);
    out.reserve(all.size());
    for (const ArraySpec &a : all) {
      Array &arr = out.emplace_back(
          Array{a.name, a.components, a.numeric, {}, std::string(info(a.type).name), false, {}});
      if (!a.numeric)
        continue;
      const std::uint64_t n = times(tuples, a.components);
      if (keep_state_types_ && kept_in_state(a.name, what == "cell data")) {
        arr.stored = true;
        auto read_as = [&]<class T>() {
          steps.add([&arr, a, n, this] { arr.ints = arrays_.read<T>(a, n); }, n);
        };
        switch (a.type) {
        case Scalar::Int8:
          read_as.template operator()<std::int8_t>();
          continue;
        case Scalar::UInt8:
          read_as.template operator()<std::uint8_t>();
          continue;
        case Scalar::Int16:
          read_as.template operator()<std::int16_t>();
          continue;
        case Scalar::UInt16:
          read_as.template operator()<std::uint16_t>();
          continue;
        case Scalar::Int32:
          read_as.template operator()<std::int32_t>();
          continue;
        default:
          arr.stored = false; // other types as doubles
        }
      }
      steps.add([&arr, a, n, this] { arr.values = arrays_.read<double>(a, n); }, n);
    }
  }

  // Appends a later piece's arrays to the first piece's, which they must match.
  void append_data(std::vector<Array> &all, std::vector<Array> &&more, bool first,
                   const std::string &what, std::size_t piece) const {
    if (first) {
      all = std::move(more);
      return;
    }
    bool same = all.size() == more.size();
    for (std::size_t i = 0; same && i < all.size(); ++i)
      same = all[i].name == more[i].name && all[i].components == more[i].components &&
             all[i].numeric == more[i].numeric;
    if (!same)
      fail("piece " + str(piece) + " has other " + what + " arrays than piece 0");
    for (std::size_t i = 0; i < all.size(); ++i)
      all[i].values.insert(all[i].values.end(), more[i].values.begin(), more[i].values.end());
  }

  const Element *child(const Element &e, std::string_view name) const {
    for (std::size_t c : e.children)
      if (doc_.elements[c].name == name)
        return &doc_.elements[c];
    return nullptr;
  }

  void read_piece(Grid &g, const Element &piece, std::size_t index, std::size_t count) {
    const std::string at = count > 1 ? "piece " + str(index) + ": " : "";
    const std::string where = count > 1 ? "piece " + str(index) : "<Piece>";
    const std::uint64_t np = parse_count(path_, piece, "NumberOfPoints", where, std::nullopt);
    const std::uint64_t nc = parse_count(path_, piece, "NumberOfCells", where, std::nullopt);
    if (np >= kNoVertex)
      fail(at + "too many points (" + str(np) + ")");

    // The arrays are read in parallel (ParallelSteps); errors come in the
    // order of the steps: Points first (their size checks NumberOfPoints
    // against the file), the cells, their check, point data, cell data.
    std::vector<double> points;
    std::vector<std::uint32_t> conn;
    std::vector<std::int64_t> offsets;
    std::vector<std::uint8_t> types;
    BadIds bad_ids;
    std::vector<Array> pd, cd;
    ParallelSteps steps;
    std::size_t check_at = std::size_t(-1);
    const Element *pd_section = child(piece, "PointData"), *cd_section = child(piece, "CellData");
    steps.plan([&] {
      const Element *pts = child(piece, "Points");
      const Element *pts_array = nullptr;
      if (pts)
        for (std::size_t c : pts->children)
          if (doc_.elements[c].name == "DataArray") {
            pts_array = &doc_.elements[c];
            break;
          }
      if (!pts_array && np > 0)
        fail(at + "the piece is missing its Points");
      if (pts_array) {
        ArraySpec a = spec(*pts_array, at + "Points");
        if (!a.numeric)
          fail(at + "Points are not numeric");
        if (a.components != 3)
          fail(at + "Points have " + std::to_string(a.components) + " components, expected 3");
        steps.add([&, a] { points = arrays_.read<double>(a, times(np, 3)); }, 3 * np);
      }
      if (const Element *cells = child(piece, "Cells")) {
        std::optional<ArraySpec> sc, so, st;
        for (const ArraySpec &a : specs(*cells, "Cells", at)) {
          if (a.name == "connectivity")
            sc = a;
          else if (a.name == "offsets")
            so = a;
          else if (a.name == "types")
            st = a;
        }
        if (nc > 0 && (!sc || !so || !st))
          fail(at + "<Cells> has no '" +
               (!sc   ? "connectivity"
                : !so ? "offsets"
                      : "types") +
               "' array");
        if (st)
          steps.add([&, a = *st] { types = arrays_.read<std::uint8_t>(a, nc); }, nc);
        if (so)
          steps.add([&, a = *so] { offsets = arrays_.read<std::int64_t>(a, nc); }, nc);
        if (sc)
          steps.add([&, a = *sc] { conn = arrays_.read<std::uint32_t>(a, kAnyCount, &bad_ids); },
                    4 * nc);
      } else if (nc > 0) {
        fail(at + "the piece is missing its Cells");
      }
      check_at = steps.size();
      plan_data(steps, pd_section, "point data", at, np, pd);
      plan_data(steps, cd_section, "cell data", at, nc, cd);
    });
    steps.run([&](std::size_t i) {
      if (i == check_at)
        check_cells(at, g.num_cells, np, conn, offsets, bad_ids);
    });

    // Concatenate, point ids and offsets shifted past the earlier pieces.
    const auto point_base = std::uint32_t(g.num_points);
    const auto conn_base = std::int64_t(g.connectivity.size());
    if (g.offsets.empty()) {
      g.offsets = std::move(offsets); // conn_base is 0
    } else {
      g.offsets.reserve(g.offsets.size() + offsets.size());
      for (std::int64_t o : offsets)
        g.offsets.push_back(o + conn_base);
    }
    if (point_base == 0) {
      if (g.connectivity.empty())
        g.connectivity = std::move(conn);
      else
        g.connectivity.insert(g.connectivity.end(), conn.begin(), conn.end());
    } else {
      for (std::uint32_t id : conn)
        g.connectivity.push_back(id + point_base); // below kNoVertex: checked
    }
    if (g.types.empty())
      g.types = std::move(types);
    else
      g.types.insert(g.types.end(), types.begin(), types.end());
    if (g.points.empty())
      g.points = std::move(points);
    else
      g.points.insert(g.points.end(), points.begin(), points.end());
    append_data(g.point_data, std::move(pd), index == 0, "point data", index);
    append_data(g.cell_data, std::move(cd), index == 0, "cell data", index);
    g.num_points += std::size_t(np);
    g.num_cells += std::size_t(nc);
    if (g.num_points >= std::size_t(kNoVertex))
      fail("too many points (" + str(g.num_points) + ")");
  }

  // Offsets end each cell: non-decreasing, within the connectivity, the last
  // at its end; every point id within the piece.
  void check_cells(const std::string &at, std::size_t first_cell, std::uint64_t np,
                   const std::vector<std::uint32_t> &conn, const std::vector<std::int64_t> &offsets,
                   const BadIds &bad) const {
    std::int64_t start = 0;
    const auto size = std::int64_t(conn.size());
    for (std::size_t c = 0; c < offsets.size(); ++c) {
      const std::int64_t end = offsets[c];
      auto cell_name = [&] { return "cell " + str(first_cell + c); };
      if (end < start)
        fail(at + "Cells array 'offsets': " + cell_name() + " ends at " + std::to_string(end) +
             ", before it starts at " + std::to_string(start) +
             " (offsets must be monotonically increasing)");
      if (end > size)
        fail(at + "Cells array 'offsets': " + cell_name() + " ends at " + std::to_string(end) +
             ", past the end of the connectivity (" + std::to_string(size) + " ids)");
      for (std::int64_t k = start; k < end; ++k)
        if (conn[std::size_t(k)] >= np) {
          const std::uint32_t id = conn[std::size_t(k)];
          fail(at + cell_name() + " refers to point " + (id == kBadId ? bad.first : str(id)) +
               ", but there are " + str(np) + " points");
        }
      start = end;
    }
    if (start != size)
      fail(at + "Cells array 'connectivity' has " + std::to_string(size) +
           " ids, but the offsets end at " + std::to_string(start));
  }

  // The arrays a StoredState takes (state.hpp), by name and place.
  static bool kept_in_state(const std::string &name, bool cell) {
    if (cell)
      return name == kStateArray || name == kMarkingArray || name == kGenerationArray;
    return name == kParentAArray || name == kParentBArray || name == kLevelArray;
  }

  const std::string &path_;
  const Document &doc_;
  FileFormat format_;
  ArrayReader arrays_;
  bool keep_state_types_ = false;
};

} // namespace

Grid parse_grid(const std::string &path, const char *data, std::size_t size,
                bool keep_state_types) {
  const Document doc = XmlParser(path, data, size).parse();
  return GridReader(path, doc, keep_state_types).read();
}

Grid read_grid(const std::string &path, bool keep_state_types) {
  const FileBytes file(path);
  return parse_grid(path, file.data(), file.size(), keep_state_types);
}

} // namespace bisect::vtu
