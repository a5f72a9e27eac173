#pragma once
// Numbers from text — one reading and one check for every format that carries them
// (scenario YAML, experiment specs, OpenSCENARIO / OpenDRIVE attributes and
// FileHeader properties, search checkpoints).
//
// A number is decimal text that is read whole, locale-independently: an optional
// sign, digits, an optional fraction and exponent ("12", "-0.5", "+3", "1e-3").
// Refused, each by name: empty text, anything else ("abc", "0x10", "1,5", "3 m"),
// NaN and infinities (also YAML's ".nan" / ".inf"), values beyond a double (1e400)
// or so small they underflow (1e-400), and — for whole numbers — fractions (1.5)
// and values outside the type (no wrap-around: -1 is not 2^64 - 1).
//
// Every refusal is one ConfigError of the shape
//   "<where>: <field>: got '<text>', expected <what> (<why>)"
// e.g. "a.xosc:12: <Dimensions>: length: got 'nan', expected a finite number in (0, 100] (NaN is not a number)".

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace vsd {

/// Bounds of a real number: [low, high] with either end open or unbounded.
struct NumberRange {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool lowOpen = false;   ///< low itself excluded
  bool highOpen = false;  ///< high itself excluded

  static constexpr NumberRange any() { return {}; }
  static constexpr NumberRange atLeast(double low) { return {low, std::numeric_limits<double>::infinity(), false, false}; }
  static constexpr NumberRange above(double low) { return {low, std::numeric_limits<double>::infinity(), true, false}; }
  static constexpr NumberRange closed(double low, double high) { return {low, high, false, false}; }
  /// (low, high]
  static constexpr NumberRange aboveUpTo(double low, double high) { return {low, high, true, false}; }

  bool contains(double value) const;
  /// "" (any), ">= 0", "> 0", "in 0 .. 100", "in (0, 100]".
  std::string text() const;
};

/// The number `text` stands for, within `range`. Throws ConfigError as above;
/// `where` locates it ("file:line" or "file:line: <element>"), `field` names it.
double parseReal(const std::string& text, const NumberRange& range, const std::string& where, const std::string& field);

/// A whole number min .. max. Integral text in real form ("3.0", "1e3") is accepted
/// up to 2^53 (beyond that a double no longer holds every integer).
std::int64_t parseInteger(const std::string& text, std::int64_t min, std::int64_t max, const std::string& where,
                          const std::string& field);

/// A whole number 0 .. max (seeds, sample indices, counts), exact up to 2^64 - 1.
std::uint64_t parseUnsigned(const std::string& text, std::uint64_t max, const std::string& where,
                            const std::string& field);

/// `value` as it reads back from its exactly rounded fixed-point text with `decimals` digits
/// (what fmt's {:.Nf} writes and a reader of that file gets), e.g. a coordinate of a network file.
double asFixedDecimalText(double value, int decimals);

/// The integer value · 10^decimals rounds to in `value`'s fixed-point text with `decimals`
/// digits (1.236 with 2 decimals: 124; -0.004: 0), where double arithmetic decides it for
/// certain: |value · 10^decimals| < 2^52 and the product not exactly on a half. std::nullopt
/// otherwise (ties and near ties, NaN, infinities, `decimals` outside 0..15): then only writing
/// the text decides. Exists so that writers of many numbers (network files) need not format
/// and parse each one.
std::optional<std::int64_t> fixedDecimalDigits(double value, int decimals);

/// 10^decimals for decimals 0..15 (exact in a double).
double powerOfTen(int decimals);

/// Room for any number fixedDecimalText writes (a double in fixed notation).
using FixedDecimalBuffer = std::array<char, 400>;

/// `value` with `decimals` (0..15) digits after the point, exactly as fmt's "{:.Nf}" writes it
/// (-0.004 with 2 decimals: "-0.00"), written into `buffer`. Cheaper than fmt where
/// fixedDecimalDigits decides the digits (the coordinates of network files); fmt writes the rest.
std::string_view fixedDecimalText(double value, int decimals, FixedDecimalBuffer& buffer);

/// Checks a number that is already a double (computed, or read by another parser)
/// against `range`, NaN and infinities included; returns it. `shown` is the text
/// the message quotes (empty: the value's shortest form).
double checkReal(double value, const NumberRange& range, const std::string& where, const std::string& field,
                 const std::string& shown = {});

/// Bounds every scenario format shares (YAML, OpenSCENARIO, OpenDRIVE): the same
/// numbers are refused whichever file carries them.
namespace scenario_bounds {
/// m: |x| of the scenario region's ends, the region's length and each road extension
/// (roads are laid out in cells of a shared SUMO network sized by them).
inline constexpr double kMaxExtent = 10'000.0;
inline constexpr NumberRange kVehicleLength = NumberRange::aboveUpTo(0.0, 100.0);  ///< m
inline constexpr NumberRange kVehicleWidth = NumberRange::aboveUpTo(0.0, 20.0);    ///< m
inline constexpr NumberRange kLaneWidth = NumberRange::aboveUpTo(0.0, 50.0);       ///< m
inline constexpr int kMaxLanes = 16;
inline constexpr NumberRange kExtension = NumberRange::closed(0.0, kMaxExtent);    ///< m
inline constexpr NumberRange kRegionEnd = NumberRange::closed(-kMaxExtent, kMaxExtent);  ///< m
/// Largest sample index a file may name: `--first-sample + --samples` stays below 2^50.
inline constexpr std::uint64_t kMaxSampleIndex = (std::uint64_t{1} << 50) - 1;
}  // namespace scenario_bounds

/// The simulation step and the number of steps of a window, checked as every format
/// checks them (bounds in vsd/core/trace.hpp: kMinStep .. kMaxStep in whole
/// milliseconds, at most kMaxWindowSteps steps) — before any array is sized by them.
/// `shown`: the text the message quotes (empty: the value's shortest form).
double checkStep(double step, const std::string& where, const std::string& field, const std::string& shown = {});
/// `duration` / `step` steps: a whole number 1 .. kMaxWindowSteps. Returns the count.
int checkDurationSteps(double duration, double step, const std::string& where, const std::string& field);

}  // namespace vsd
