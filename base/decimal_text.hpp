// Numbers as people write them: [+-] digits [. digits] [(e|E) [+-] digits].
// strtod also reads hexadecimal ("0x1A" is 26, "0x1p3" is 8), "inf", "nan"
// and leading blanks, which in a path file, a script or on a command line are
// mistakes, not values. One rule for all of visvol's text inputs.
#pragma once

#include <cctype>
#include <string_view>

namespace visvol {

inline bool is_decimal_number(std::string_view s) {
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t from = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    return i - from;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == s.size();
}

// "inf", "infinity", "nan" in any case, with a sign: words a range check
// should name rather than a parser refuse.
inline bool is_non_finite_word(std::string_view s) {
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
  auto same = [&](std::string_view word) {
    if (s.size() != word.size()) return false;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (std::tolower(static_cast<unsigned char>(s[i])) != word[i]) return false;
    }
    return true;
  };
  return same("inf") || same("infinity") || same("nan");
}

}  // namespace visvol
