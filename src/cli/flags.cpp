#include "flags.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace vsd::cli {

namespace {

std::string expectedInteger(std::int64_t min, std::uint64_t max) {
  return fmt::format("expected a whole number {} .. {}", min, max);
}

}  // namespace

std::string checkIntegerText(std::string& text, std::int64_t min, std::uint64_t max) {
  const std::string original = text;
  const auto refuse = [&] { return fmt::format("got '{}', {}", original, expectedInteger(min, max)); };
  std::string digits = text;
  bool negative = false;
  if (!digits.empty() && (digits[0] == '+' || digits[0] == '-')) {
    negative = digits[0] == '-';
    digits.erase(0, 1);
  }
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return refuse();
  // Leading zeros would make CLI11 read octal (strtoull with base 0): drop them.
  const auto first = digits.find_first_not_of('0');
  digits = first == std::string::npos ? "0" : digits.substr(first);
  if (digits == "0") negative = false;
  errno = 0;
  if (negative) {
    const long long value = std::strtoll(("-" + digits).c_str(), nullptr, 10);
    if (errno == ERANGE || value < min) return refuse();
  } else {
    const unsigned long long value = std::strtoull(digits.c_str(), nullptr, 10);
    if (errno == ERANGE || value > max) return refuse();
  }
  text = (negative ? "-" : "") + digits;
  return {};
}

std::string checkRealText(const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  // strtod also takes hexadecimal floats ("0x1p3"): a flag's value is decimal.
  const bool decimal = text.find_first_of("xX") == std::string::npos;
  if (text.empty() || end != begin + text.size() || !decimal || !std::isfinite(value) || errno == ERANGE) {
    // ERANGE also flags underflow to a denormal (1e-400): refused as well, nobody means it.
    return fmt::format("got '{}', expected a finite decimal number", text);
  }
  return {};
}

}  // namespace vsd::cli
