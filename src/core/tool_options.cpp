#include "vsd/core/tool_options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>
#include <optional>

#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"

namespace vsd {

namespace {

/// What follows an allowed option.
enum class Value {
  Flag,    ///< nothing, or true / false
  Number,  ///< one finite number
  Words,   ///< plain words or numbers (letters, digits, spaces, '.', '_', '+', '-'): never a path
};

struct AllowedOption {
  const char* name;
  Value value;
};

// Options that tune the simulation; none names a file, folder, prefix or port.
constexpr AllowedOption kSumoOptions[] = {
    {"--precision", Value::Number},
    {"--precision.geo", Value::Number},
    {"--seed", Value::Number},
    {"--lateral-resolution", Value::Number},
    {"--step-method.ballistic", Value::Flag},
    {"--default.action-step-length", Value::Number},
    {"--default.speeddev", Value::Number},
    {"--default.carfollowmodel", Value::Words},
    {"--collision.mingap-factor", Value::Number},
    {"--collision.check-junctions", Value::Flag},
    {"--collision.stoptime", Value::Number},
    {"--time-to-teleport", Value::Number},
    {"--time-to-impatience", Value::Number},
    {"--max-depart-delay", Value::Number},
    {"--eager-insert", Value::Flag},
    {"--ignore-route-errors", Value::Flag},
    {"--emergencydecel.warning-threshold", Value::Number},
    {"--device.ssm.probability", Value::Number},
    {"--device.ssm.measures", Value::Words},
    {"--device.ssm.thresholds", Value::Words},
    {"--device.ssm.range", Value::Number},
    {"--device.ssm.extratime", Value::Number},
    {"--device.ssm.trajectories", Value::Flag},
    {"--device.ssm.geo", Value::Flag},
};

// Options that shape the network; none names a file, folder or prefix.
constexpr AllowedOption kNetconvertOptions[] = {
    {"--precision", Value::Number},
    {"--default.lanewidth", Value::Number},
    {"--default.speed", Value::Number},
    {"--default.junctions.radius", Value::Number},
    {"--junctions.corner-detail", Value::Number},
    {"--junctions.internal-link-detail", Value::Number},
    {"--junctions.limit-turn-speed", Value::Number},
    {"--junctions.join", Value::Flag},
    {"--no-turnarounds", Value::Flag},
    {"--no-internal-links", Value::Flag},
    {"--rectangular-lane-cut", Value::Flag},
    {"--geometry.remove", Value::Flag},
    {"--geometry.min-radius.fix", Value::Flag},
    {"--geometry.max-grade.fix", Value::Flag},
    {"--opendrive.curve-resolution", Value::Number},
};

template <std::size_t N>
std::vector<AllowedOption> listOf(const AllowedOption (&options)[N]) {
  return std::vector<AllowedOption>(options, options + N);
}

std::vector<AllowedOption> allowed(SumoTool tool) {
  return tool == SumoTool::Sumo ? listOf(kSumoOptions) : listOf(kNetconvertOptions);
}

const char* toolName(SumoTool tool) { return tool == SumoTool::Sumo ? "SUMO" : "netconvert"; }

std::optional<AllowedOption> find(SumoTool tool, const std::string& name) {
  for (const auto& option : allowed(tool)) {
    if (name == option.name) return option;
  }
  return std::nullopt;
}

bool isPlainWords(const std::string& text) {
  return !text.empty() && text.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 ._+-") ==
                              std::string::npos;
}

/// Checks `value` of `option`; throws naming the option and what it takes.
void checkValue(const AllowedOption& option, const std::string& value, const std::string& where,
                const std::string& item) {
  switch (option.value) {
    case Value::Flag:
      if (value != "true" && value != "false") throw ConfigError::field(where, item, value, fmt::format("true or false after {}", option.name));
      return;
    case Value::Number:
      parseReal(value, NumberRange::any(), where, fmt::format("{} (value of {})", item, option.name));
      return;
    case Value::Words:
      if (!isPlainWords(value)) {
        throw ConfigError::field(where, item, value,
                                 fmt::format("plain words or numbers after {} (letters, digits, spaces, . _ + -)", option.name));
      }
      return;
  }
}

}  // namespace

namespace {
constexpr const char* kCollisionActions[] = {"none", "warn", "teleport", "remove"};
}  // namespace

bool isCollisionAction(const std::string& action) {
  return std::any_of(std::begin(kCollisionActions), std::end(kCollisionActions),
                     [&](const char* known) { return action == known; });
}

std::string collisionActionsExpected() { return fmt::format("one of {}", fmt::join(kCollisionActions, ", ")); }

std::string allowedToolOptions(SumoTool tool) {
  std::vector<std::string> names;
  for (const auto& option : allowed(tool)) names.emplace_back(option.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

void checkScenarioToolOptions(SumoTool tool, const std::vector<std::string>& options, const std::string& where,
                              const std::string& field) {
  for (std::size_t i = 0; i < options.size(); ++i) {
    const std::string item = fmt::format("{}[{}]", field, i);
    const std::string& token = options[i];
    const auto equals = token.find('=');
    const std::string name = token.substr(0, equals);
    const auto option = find(tool, name);
    if (!option) {
      throw ConfigError::field(
          where, item, token,
          fmt::format("an option a scenario file may pass to {} (one that names no file, folder or port: {})", toolName(tool),
                      allowedToolOptions(tool)));
    }
    if (equals != std::string::npos) {
      checkValue(*option, token.substr(equals + 1), where, item);
      continue;
    }
    const bool has_next = i + 1 < options.size() && options[i + 1].rfind("--", 0) != 0;
    if (option->value == Value::Flag && !has_next) continue;
    if (!has_next) throw ConfigError::field(where, item, token, fmt::format("a value after {}", option->name));
    ++i;
    checkValue(*option, options[i], where, fmt::format("{}[{}]", field, i));
  }
}

}  // namespace vsd
