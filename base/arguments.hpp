// Checks on a program's command line before it is parsed.
#pragma once

namespace visvol {

// The index of the first empty argument (""), or 0 when there is none. No
// option or operand of visvol's programs takes an empty value, and CLI11
// reads one as the option's default: `--clearance ''` planned at the default
// 30 m without a word.
inline int first_empty_argument(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i][0] == '\0') return i;
  }
  return 0;
}

}  // namespace visvol
