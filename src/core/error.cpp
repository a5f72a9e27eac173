#include "vsd/core/error.hpp"

#include <fmt/format.h>

namespace vsd {

ConfigError ConfigError::field(const std::string& where, const std::string& field, const std::string& value,
                               const std::string& expected) {
  return ConfigError(fmt::format("{}: {}: got '{}', expected {}", where, field, value, expected));
}

std::string formatValue(double value) { return fmt::format("{}", value); }

}  // namespace vsd
