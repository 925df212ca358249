// Text for messages, shared by the library, the command line and pybisect.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>

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
