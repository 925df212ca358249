// Text for messages, shared by the library, the command line and pybisect.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace bisect {

// An error message as one line: control characters a hostile file put into
// it (a newline inside an attribute) are shown escaped.
inline std::string one_line(const std::string &text) {
  std::string out;
  for (unsigned char c : text) {
    if (c == '\n')
      out += "\\n";
    else if (c == '\r')
      out += "\\r";
    else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    } else
      out += char(c);
  }
  return out;
}

// Whether `s` is a name an XML attribute keeps as it is: well-formed UTF-8
// (shortest forms, no surrogates, at most U+10FFFF, neither U+FFFE nor
// U+FFFF) without control characters (a tab or a newline would come back
// from an XML reader as a space). Array and physical names go into .vtu
// attributes; VTK reads no cells from a file with a name that is not.
inline bool is_name_text(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c == 0x7f)
      return false;
    if (c < 0x80) {
      ++i;
      continue;
    }
    const int more = c >= 0xC2 && c <= 0xDF   ? 1
                     : c >= 0xE0 && c <= 0xEF ? 2
                     : c >= 0xF0 && c <= 0xF4 ? 3
                                              : -1;
    if (more < 0 || s.size() - i <= std::size_t(more))
      return false;
    unsigned code = c & (0x3Fu >> more);
    for (int k = 1; k <= more; ++k) {
      const unsigned char t = static_cast<unsigned char>(s[i + std::size_t(k)]);
      if ((t & 0xC0) != 0x80)
        return false;
      code = code << 6 | (t & 0x3F);
    }
    const unsigned least = more == 1 ? 0x80 : more == 2 ? 0x800 : 0x10000;
    if (code < least || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF) || code == 0xFFFE ||
        code == 0xFFFF)
      return false;
    i += std::size_t(more) + 1;
  }
  return true;
}

// A name for a message: printable ASCII as it is, every other byte as \xNN.
inline std::string shown_name(std::string_view s) {
  std::string out;
  for (unsigned char c : s) {
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    }
  }
  return out;
}

// 1234567 -> "1,234,567".
inline std::string with_commas(std::size_t n) {
  const std::string digits = std::to_string(n);
  std::string s;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0)
      s += ',';
    s += digits[i];
  }
  return s;
}

} // namespace bisect
