// Text from outside (a file's bytes, a name, an option's value) as it may
// reach an operator's terminal or a log: no escape sequence in a file can
// drive the terminal, and no token of megabytes floods it.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace visvol {

// `text` with every control character shown as \xNN: C0 (but the newline, so
// that messages keep their lines), DEL, C1 as UTF-8 writes it (0xC2
// 0x80..0x9F; a terminal reads U+009B as CSI) and any byte that is not part
// of a whole UTF-8 character (a lone 0x9B is CSI to an 8-bit terminal).
// Other characters stay. Longer than `max_bytes`: cut there, with the length
// said.
inline std::string terminal_safe(std::string_view text, std::size_t max_bytes = 4096) {
  std::string out;
  std::size_t n = text.size() > max_bytes ? max_bytes : text.size();
  // cut between characters: not inside a UTF-8 sequence (3 bytes back at most)
  for (int k = 0; k < 3 && n > 0 && n < text.size() && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80; ++k) --n;
  out.reserve(n + 16);
  auto hex = [&](unsigned c) {
    char code[8];
    std::snprintf(code, sizeof code, "\\x%02X", c);
    out += code;
  };
  auto at = [&](std::size_t i) { return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u; };
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned c = at(i);
    // a UTF-8 character's length from its first byte (0: not a first byte,
    // a byte an 8-bit terminal may read as C1, 0x9B its CSI)
    const std::size_t length = c < 0x80                 ? 1
                               : c >= 0xC2 && c <= 0xDF ? 2
                               : c >= 0xE0 && c <= 0xEF ? 3
                               : c >= 0xF0 && c <= 0xF4 ? 4
                                                        : 0;
    bool whole = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; whole && k < length; ++k) whole = (at(i + k) & 0xC0) == 0x80;
    // and the shortest form of a code point of Unicode: no overlong form (E0
    // 80..9F, F0 80..8F), no surrogate (ED A0..BF), nothing past U+10FFFF (F4 90..)
    const unsigned second = at(i + 1);
    if (whole && ((c == 0xE0 && second < 0xA0) || (c == 0xED && second > 0x9F) || (c == 0xF0 && second < 0x90) ||
                  (c == 0xF4 && second > 0x8F))) {
      whole = false;
    }
    const bool c1 = c == 0xC2 && whole && at(i + 1) <= 0x9F;  // U+0080..U+009F
    if (!whole || c1) {
      hex(c);  // (a C1 character's second byte follows as a byte of no character)
    } else if ((c < 0x20 && c != '\n') || c == 0x7F) {
      hex(c);
    } else {
      out.append(text.substr(i, length));
      i += length - 1;
    }
  }
  if (text.size() > n) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace visvol
