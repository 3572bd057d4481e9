// Checks on a program's command line before it is parsed (start-up only:
// empty_argument_problem allocates).
#pragma once

#include <cstring>
#include <string>

namespace visvol {

// The index of the first empty argument ("", or "--option=" with nothing
// after the '='), or 0 when there is none. CLI11 reads an empty value as the
// option's default (`--clearance ''` planned at the default 30 m without a
// word) and `--option=` as taking the next argument. `may_be_empty` names
// the options whose value may be empty (null-terminated list; every
// program's --namespace, empty by default).
inline int first_empty_argument(int argc, char** argv, const char* const* may_be_empty = nullptr) {
  auto allowed = [&](const char* option, std::size_t length) {
    for (const char* const* o = may_be_empty; o != nullptr && *o != nullptr; ++o) {
      if (std::strlen(*o) == length && std::strncmp(*o, option, length) == 0) return true;
    }
    return false;
  };
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const std::size_t n = std::strlen(a);
    if (n == 0 && !(i > 1 && allowed(argv[i - 1], std::strlen(argv[i - 1])))) return i;
    if (n > 2 && a[0] == '-' && a[1] == '-' && a[n - 1] == '=' && !allowed(a, n - 1)) return i;
  }
  return 0;
}

// What first_empty_argument found, for the program's one line on stderr.
inline std::string empty_argument_problem(char** argv, int index) {
  const std::string where = "argument " + std::to_string(index);
  if (argv[index][0] != '\0') return where + ", '" + argv[index] + "', has an empty value: give it one";
  return where + (index > 1 ? std::string(" after ") + argv[index - 1] : std::string()) + " is empty: give it a value";
}

}  // namespace visvol
