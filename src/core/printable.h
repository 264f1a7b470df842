#pragma once
// Text from an input file quoted in an error message (one line): every control character (newline,
// carriage return, tab, escape …) becomes '?', and a long quote is cut, so a message stays one printable line
// whatever the file holds.
#include <cstddef>
#include <string>
#include <string_view>

namespace ff {

/// `s` with control characters as '?', cut after `max` characters (then "...").
inline std::string printable(std::string_view s, std::size_t max = 64) {
  std::string out(s.substr(0, max));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  if (s.size() > max) out += "...";
  return out;
}

}  // namespace ff
