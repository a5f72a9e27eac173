#include "vsd/report/numbers.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace vsd::report {

int decimalsFor(double spread) {
  if (!(spread > 0.0) || !std::isfinite(spread)) return 2;
  return std::clamp(2 - static_cast<int>(std::floor(std::log10(spread))), 0, 4);
}

std::string percentWithInterval(double share, double low, double high) {
  if (!std::isfinite(share) || !std::isfinite(low) || !std::isfinite(high)) return "-";
  const int decimals = decimalsFor(100.0 * (high - low));
  return fmt::format("{:.{}f} % [{:.{}f}, {:.{}f}] %", 100.0 * share, decimals, 100.0 * low, decimals, 100.0 * high,
                     decimals);
}

}  // namespace vsd::report
