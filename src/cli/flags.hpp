#pragma once
// Numeric flags that refuse what their C++ type cannot hold. CLI11 2.1 converts
// an unsigned flag with strtoull, so `--seed -1` silently becomes 2^64 - 1, reads
// `010` as octal 8, and takes `inf`/`nan` for floating-point flags. Every numeric
// flag is added through addNumber(), whose check accepts only a plain decimal
// number that the type holds exactly (integers: digits with an optional sign, no
// sign for unsigned types; floating point: finite). Ranges (what a value may
// mean) are checked by the library's Options::validate(), their single source.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace vsd::cli {

/// Checks and normalises the text of an integer flag; empty string = accepted.
/// `min`/`max`: what the type holds (a leading '-' only if min < 0).
std::string checkIntegerText(std::string& text, std::int64_t min, std::uint64_t max);
/// Checks the text of a floating-point flag (finite decimal number); empty string = accepted.
std::string checkRealText(const std::string& text);

/// The check for a flag of type T (integral or floating point).
template <typename T>
CLI::Validator numberCheck() {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "numberCheck is for numeric flags");
  if constexpr (std::is_floating_point_v<T>) {
    return CLI::Validator([](std::string& text) { return checkRealText(text); }, "", "number");
  } else {
    return CLI::Validator(
        [](std::string& text) {
          return checkIntegerText(text, static_cast<std::int64_t>(std::numeric_limits<T>::min()),
                                  static_cast<std::uint64_t>(std::numeric_limits<T>::max()));
        },
        "", "number");
  }
}

/// add_option for a numeric flag (or positional), with numberCheck<T>() applied
/// before CLI11 converts the text.
template <typename T>
CLI::Option* addNumber(CLI::App* app, const std::string& names, T& value, const std::string& help) {
  return app->add_option(names, value, help)->transform(numberCheck<T>());
}

/// addNumber for a list flag (every element checked).
template <typename T>
CLI::Option* addNumber(CLI::App* app, const std::string& names, std::vector<T>& values, const std::string& help) {
  return app->add_option(names, values, help)->transform(numberCheck<T>());
}

}  // namespace vsd::cli
