// Numbers on a command line and in a configuration file are decimal.
//
// CLI11 converts an integer with strtoll(..., 0): "--segments 010" was 8
// (octal), "0x10" was 16, and an unsigned option took "-1" as 2^64 - 1; a
// float goes through strtold, which reads "0x10" as sixteen. A crew types
// "010" meaning ten. decimal_numbers() gives every numeric option of an
// application and of its subcommands a transform that runs before its other
// checks: an integer keeps its decimal digits only (leading zeros dropped,
// so "010" is ten), anything else is refused naming the value; a real number
// must be decimal (base/decimal_text.hpp) or a word for infinity or NaN. Options with a type name of their own (not
// "INT", "UINT" or "FLOAT") get decimal_integers() or decimal_reals() by hand.
//
// Start-up only (allocates).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "base/decimal_text.hpp"

namespace visvol {

namespace decimal_text {

// "" when `v` is a decimal integer (then made plain: no sign '+', no leading
// zeros), else the problem.
inline std::string plain_decimal_integer(std::string& v, bool may_be_negative) {
  std::size_t i = 0;
  const bool negative = !v.empty() && v[0] == '-';
  if (!v.empty() && (v[0] == '+' || v[0] == '-')) i = 1;
  const std::size_t first_digit = i;
  while (i < v.size() && v[i] >= '0' && v[i] <= '9') ++i;
  if (i == first_digit || i != v.size()) return "'" + v + "' is not a whole number in decimal digits";
  if (negative && !may_be_negative) return "'" + v + "' is negative";
  std::size_t lead = first_digit;
  while (lead + 1 < v.size() && v[lead] == '0') ++lead;  // "010" is ten, not octal eight
  v = (negative ? "-" : "") + v.substr(lead);
  return {};
}

// Decimal, or a word for infinity or NaN (the option's own check names its
// range): strtold also reads " 0x10" as sixteen.
inline std::string decimal_real(const std::string& v) {
  if (is_decimal_number(v) || is_non_finite_word(v)) return {};
  return "'" + v + "' is not a number in decimal";
}

}  // namespace decimal_text

inline void decimal_integers(CLI::Option* option, bool may_be_negative) {
  option->transform(CLI::Validator(
      [may_be_negative](std::string& v) { return decimal_text::plain_decimal_integer(v, may_be_negative); }, "", ""));
}

inline void decimal_reals(CLI::Option* option) {
  option->transform(CLI::Validator([](std::string& v) { return decimal_text::decimal_real(v); }, "", ""));
}

// Every option of `app` and of its subcommands, at any depth, whose type is
// a number. Call once, after every option is declared.
inline void decimal_numbers(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    if (option->get_type_size_max() == 0) continue;  // a flag
    const std::string type = option->get_type_name();
    auto starts = [&](const char* prefix) { return type.rfind(prefix, 0) == 0; };
    if (starts("UINT")) {
      decimal_integers(option, false);
    } else if (starts("INT")) {
      decimal_integers(option, true);
    } else if (starts("FLOAT")) {
      decimal_reals(option);
    }
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) decimal_numbers(*sub);
}

}  // namespace visvol
