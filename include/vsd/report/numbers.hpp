#pragma once
// Figures printed for people: as many digits as the uncertainty makes meaningful.

#include <string>

namespace vsd::report {

/// Decimals that show `spread` (> 0; e.g. an interval's width) with three significant
/// digits (a tenth of the spread is the last digit that means anything), clamped to 0 .. 4.
int decimalsFor(double spread);

/// A share (0..1) as a percentage with its interval, e.g. "10.4 % [2.5, 18.4] %": the
/// decimals follow the interval's width (decimalsFor). NaN or infinite parts: "-".
std::string percentWithInterval(double share, double low, double high);

}  // namespace vsd::report
