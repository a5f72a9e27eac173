#pragma once
// One exception root for the whole project. The CLI turns any vsd::Error into a
// single line on stderr and a non-zero exit code, so every message must stand on
// its own: name the file, the key or field, the bad value and what was expected.

#include <stdexcept>
#include <string>

namespace vsd {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Invalid user configuration: scenario YAML, experiment YAML, CLI flags.
class ConfigError : public Error {
 public:
  using Error::Error;
  /// "<where>: <field>: got '<value>', expected <expected>"
  static ConfigError field(const std::string& where, const std::string& field, const std::string& value,
                           const std::string& expected);
};

/// SUMO, netconvert or libsumo refused something or failed.
class SumoError : public Error {
 public:
  using Error::Error;
};

/// A dataset, trace or CSV file is missing, corrupt, foreign or of an unknown schema.
class DatasetError : public Error {
 public:
  using Error::Error;
};

/// A model file is corrupt, incompatible, or training/prediction cannot proceed.
class ModelError : public Error {
 public:
  using Error::Error;
};

/// A file could not be read, written or renamed.
class IoError : public Error {
 public:
  using Error::Error;
};

/// Renders a double for error messages the way a user wrote it (shortest exact form).
std::string formatValue(double value);

}  // namespace vsd
