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
// that messages keep their lines), DEL, and C1 as UTF-8 writes it (0xC2
// 0x80..0x9F; a terminal reads U+009B as CSI). Other bytes, UTF-8 included,
// stay. Longer than `max_bytes`: cut there, with the length said.
inline std::string terminal_safe(std::string_view text, std::size_t max_bytes = 4096) {
  std::string out;
  std::size_t n = text.size() > max_bytes ? max_bytes : text.size();
  // cut between characters: not inside a UTF-8 sequence
  while (n > 0 && n < text.size() && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;
  out.reserve(n + 16);
  auto hex = [&](unsigned char c) {
    char code[8];
    std::snprintf(code, sizeof code, "\\x%02X", static_cast<unsigned>(c));
    out += code;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const bool c1 = c == 0xC2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                    static_cast<unsigned char>(text[i + 1]) <= 0x9F;
    if (c1) {
      hex(c);
      hex(static_cast<unsigned char>(text[++i]));
    } else if ((c < 0x20 && c != '\n') || c == 0x7F) {
      hex(c);
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > n) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace visvol
