#include "vsd/core/numbers.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>

#include "vsd/core/error.hpp"
#include "vsd/core/trace.hpp"

namespace vsd {

namespace {

/// 2^53: beyond it a double does not hold every integer.
constexpr double kExactIntegerLimit = 9007199254740992.0;

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

/// Why `text` names no finite double (NaN, infinity), by name; empty if it does not name one.
std::string specialName(const std::string& text) {
  std::string body = lower(text);
  if (!body.empty() && (body[0] == '+' || body[0] == '-')) body.erase(0, 1);
  if (!body.empty() && body[0] == '.') body.erase(0, 1);  // YAML's .nan / .inf
  if (body == "nan" || body.rfind("nan(", 0) == 0) return "NaN is not a number";
  if (body == "inf" || body == "infinity") return "infinite";
  return {};
}

struct Reading {
  std::optional<double> value;
  std::string why;  ///< set when value is empty
};

/// Reads the whole of `text` as a finite decimal double.
Reading readDecimal(const std::string& text) {
  if (text.empty()) return {std::nullopt, "empty"};
  if (const std::string name = specialName(text); !name.empty()) return {std::nullopt, name};
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (*begin == '+') ++begin;  // from_chars takes '-' only
  if (begin == end || !(std::isdigit(static_cast<unsigned char>(*begin)) || *begin == '-' || *begin == '.')) {
    return {std::nullopt, "not a decimal number"};
  }
  double value = 0.0;
  const auto [stop, error] = std::from_chars(begin, end, value, std::chars_format::general);
  if (error == std::errc::result_out_of_range) {
    // from_chars reports both overflow and underflow; the digits tell which.
    errno = 0;
    const double magnitude = std::strtod(text.c_str(), nullptr);
    return {std::nullopt, std::isinf(magnitude) ? "beyond the range of a double" : "too small to tell from 0 in a double"};
  }
  if (error != std::errc() || stop != end) return {std::nullopt, "not a decimal number"};
  if (!std::isfinite(value)) return {std::nullopt, "infinite"};
  return {value, {}};
}

[[noreturn]] void refuse(const std::string& where, const std::string& field, const std::string& text,
                         const std::string& expected, const std::string& why) {
  throw ConfigError::field(where, field, text, why.empty() ? expected : fmt::format("{} ({})", expected, why));
}

std::string realExpected(const NumberRange& range) {
  const std::string bounds = range.text();
  return bounds.empty() ? "a finite number" : "a finite number " + bounds;
}

std::string integerExpected(std::int64_t min, std::uint64_t max) { return fmt::format("a whole number {} .. {}", min, max); }

/// Digits only (after an optional sign): the exact value, or why not.
std::optional<std::uint64_t> exactDigits(const std::string& digits, bool& overflow) {
  overflow = false;
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  std::uint64_t value = 0;
  const auto [stop, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value, 10);
  if (error == std::errc::result_out_of_range) {
    overflow = true;
    return std::nullopt;
  }
  if (error != std::errc() || stop != digits.data() + digits.size()) return std::nullopt;
  return value;
}

/// A whole number as sign and magnitude; throws as parseInteger/parseUnsigned do.
std::pair<bool, std::uint64_t> wholeNumber(const std::string& text, const std::string& where, const std::string& field,
                                           const std::string& expected) {
  std::string digits = text;
  bool negative = false;
  if (!digits.empty() && (digits[0] == '+' || digits[0] == '-')) {
    negative = digits[0] == '-';
    digits.erase(0, 1);
  }
  bool overflow = false;
  if (const auto exact = exactDigits(digits, overflow)) return {negative && *exact != 0, *exact};
  if (overflow) refuse(where, field, text, expected, "out of range");
  const Reading reading = readDecimal(text);
  if (!reading.value) refuse(where, field, text, expected, reading.why);
  const double value = *reading.value;
  if (value != std::floor(value)) refuse(where, field, text, expected, "a fraction");
  if (std::abs(value) > kExactIntegerLimit) refuse(where, field, text, expected, "out of range");
  return {value < 0.0, static_cast<std::uint64_t>(std::abs(value))};
}

std::string shortest(double value) { return fmt::format("{}", value); }

}  // namespace

bool NumberRange::contains(double value) const {
  if (std::isnan(value)) return false;
  const bool above_low = lowOpen ? value > low : value >= low;
  const bool below_high = highOpen ? value < high : value <= high;
  return above_low && below_high;
}

std::string NumberRange::text() const {
  const bool has_low = std::isfinite(low);
  const bool has_high = std::isfinite(high);
  if (!has_low && !has_high) return {};
  if (!has_high) return fmt::format("{} {}", lowOpen ? ">" : ">=", shortest(low));
  if (!has_low) return fmt::format("{} {}", highOpen ? "<" : "<=", shortest(high));
  if (!lowOpen && !highOpen) return fmt::format("in {} .. {}", shortest(low), shortest(high));
  return fmt::format("in {}{}, {}{}", lowOpen ? "(" : "[", shortest(low), shortest(high), highOpen ? ")" : "]");
}

double parseReal(const std::string& text, const NumberRange& range, const std::string& where, const std::string& field) {
  const Reading reading = readDecimal(text);
  if (!reading.value) refuse(where, field, text, realExpected(range), reading.why);
  if (!range.contains(*reading.value)) refuse(where, field, text, realExpected(range), {});
  return *reading.value;
}

std::int64_t parseInteger(const std::string& text, std::int64_t min, std::int64_t max, const std::string& where,
                          const std::string& field) {
  const std::string expected = integerExpected(min, static_cast<std::uint64_t>(std::max<std::int64_t>(max, 0)));
  const auto [negative, magnitude] = wholeNumber(text, where, field, expected);
  constexpr auto kLargest = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  if (magnitude > kLargest + (negative ? 1U : 0U)) refuse(where, field, text, expected, "out of range");
  const std::int64_t value =
      negative ? (magnitude == kLargest + 1U ? std::numeric_limits<std::int64_t>::min() : -static_cast<std::int64_t>(magnitude))
               : static_cast<std::int64_t>(magnitude);
  if (value < min || value > max) refuse(where, field, text, expected, {});
  return value;
}

std::uint64_t parseUnsigned(const std::string& text, std::uint64_t max, const std::string& where,
                            const std::string& field) {
  const std::string expected = integerExpected(0, max);
  const auto [negative, magnitude] = wholeNumber(text, where, field, expected);
  if (negative || magnitude > max) refuse(where, field, text, expected, {});
  return magnitude;
}

double checkReal(double value, const NumberRange& range, const std::string& where, const std::string& field,
                 const std::string& shown) {
  const std::string text = shown.empty() ? shortest(value) : shown;
  if (std::isnan(value)) refuse(where, field, text, realExpected(range), "NaN is not a number");
  if (std::isinf(value)) refuse(where, field, text, realExpected(range), "infinite");
  if (!range.contains(value)) refuse(where, field, text, realExpected(range), {});
  return value;
}

double checkStep(double step, const std::string& where, const std::string& field, const std::string& shown) {
  const std::string expected = fmt::format("a multiple of {0} s in {0} .. {1} s", kMinStep, kMaxStep);
  const std::string text = shown.empty() ? shortest(step) : shown;
  if (!std::isfinite(step)) refuse(where, field, text, expected, std::isnan(step) ? "NaN is not a number" : "infinite");
  // SUMO counts milliseconds.
  const double milliseconds = step / kMinStep;
  if (!(step >= kMinStep && step <= kMaxStep) || std::abs(milliseconds - std::round(milliseconds)) > 1e-6) {
    refuse(where, field, text, expected, {});
  }
  return step;
}

int checkDurationSteps(double duration, double step, const std::string& where, const std::string& field) {
  const std::string expected =
      fmt::format("a whole multiple of the step ({} s), 1 .. {} steps ({} s at most)", shortest(step), kMaxWindowSteps,
                  shortest(step * kMaxWindowSteps));
  if (!std::isfinite(duration)) {
    refuse(where, field, shortest(duration), expected, std::isnan(duration) ? "NaN is not a number" : "infinite");
  }
  const double steps = duration / step;
  if (!(steps >= 1.0 - 1e-6) || steps > kMaxWindowSteps + 0.5 || std::abs(steps - std::round(steps)) > 1e-6) {
    refuse(where, field, shortest(duration), expected, {});
  }
  return static_cast<int>(std::lround(steps));
}

double powerOfTen(int decimals) {
  static constexpr double kPowers[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  if (decimals < 0 || decimals > 15) throw Error(fmt::format("internal: 10^{} asked for (0..15 supported)", decimals));
  return kPowers[decimals];
}

std::optional<std::int64_t> fixedDecimalDigits(double value, int decimals) {
  // Below 2^52 every n + 0.5 is a double, and rounding the product to the nearest double is
  // monotonic: the computed product lies on the same side of each n + 0.5 as the exact one, or
  // on it. Only a product that lands on a half is undecided (an exact tie or a near one).
  constexpr double kLimit = 4503599627370496.0;  // 2^52
  if (decimals < 0 || decimals > 15) return std::nullopt;
  const double scaled = value * powerOfTen(decimals);
  if (!(std::abs(scaled) < kLimit)) return std::nullopt;  // also NaN
  const double below = std::floor(scaled);
  // In [0, 1]: exact, but for a product in (-1, 0), where it is rounded - monotonically, and one
  // half is a double, so it still lies on the exact fraction's side of one half, or on it.
  const double fraction = scaled - below;
  if (fraction == 0.5) return std::nullopt;
  return static_cast<std::int64_t>(fraction < 0.5 ? below : below + 1.0);
}

std::string_view fixedDecimalText(double value, int decimals, FixedDecimalBuffer& buffer) {
  const double scale_of_digits = powerOfTen(decimals);  // also refuses decimals outside 0..15
  const auto digits = fixedDecimalDigits(value, decimals);
  if (!digits) {
    const auto written = fmt::format_to_n(buffer.data(), buffer.size(), "{:.{}f}", value, decimals);
    return {buffer.data(), std::min(written.size, buffer.size())};
  }
  const auto scale = static_cast<std::int64_t>(scale_of_digits);
  const std::int64_t magnitude = *digits < 0 ? -*digits : *digits;
  char* end = buffer.data();
  if (std::signbit(value)) *end++ = '-';  // also for a value that rounds to zero, as fmt writes it
  end = std::to_chars(end, buffer.data() + buffer.size(), magnitude / scale).ptr;
  if (decimals == 0) return {buffer.data(), static_cast<std::size_t>(end - buffer.data())};
  *end++ = '.';
  std::int64_t fraction = magnitude % scale;
  for (int d = decimals - 1; d >= 0; --d, fraction /= 10) end[d] = static_cast<char>('0' + fraction % 10);
  end += decimals;
  return {buffer.data(), static_cast<std::size_t>(end - buffer.data())};
}

double asFixedDecimalText(double value, int decimals) {
  if (const auto digits = fixedDecimalDigits(value, decimals)) {
    // The text "digits / 10^decimals" reads back as the double nearest to that quotient, which
    // is what the correctly rounded division gives; a zero keeps the sign the text writes.
    if (*digits == 0) return std::copysign(0.0, value);
    return static_cast<double>(*digits) / powerOfTen(decimals);
  }
  char text[400];  // room for any double in fixed notation
  const auto end = std::to_chars(text, text + sizeof(text), value, std::chars_format::fixed, decimals).ptr;
  double parsed = 0.0;
  std::from_chars(text, end, parsed);
  return parsed;
}

}  // namespace vsd
