// Validation of model configurations and training options; --mix and --decoder-option parsing.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/model/options.hpp"

namespace vsd::model {

const std::vector<std::string>& availableFrames() {
  static const std::vector<std::string> kFrames = {"ego", "lane"};
  return kFrames;
}

const DecoderRegistry& VectorNetConfig::decoderRegistry() const {
  if (!decoders) throw ConfigError("model configuration: no decoder registry (VectorNetConfig::decoders is empty)");
  return *decoders;
}

double VectorNetConfig::decoderOption(const std::string& name) const {
  const auto& info = decoderRegistry().find(decoder, "model configuration");
  for (const auto& option : info.options) {
    if (option.name != name) continue;
    const auto given = decoderOptions.find(name);
    return given == decoderOptions.end() ? option.defaultValue : given->second;
  }
  throw ConfigError(fmt::format("decoder '{}' has no option '{}'", decoder, name));
}

namespace {

void validateDecoderOptions(const DecoderInfo& info, const std::map<std::string, double>& given) {
  for (const auto& [name, value] : given) {
    const auto option = std::find_if(info.options.begin(), info.options.end(),
                                     [&](const DecoderOption& o) { return o.name == name; });
    if (option == info.options.end()) {
      std::vector<std::string> known;
      for (const auto& o : info.options) known.push_back(o.name);
      throw ConfigError(fmt::format("--decoder-option {}: decoder '{}' has no option '{}' (its options: {})", name,
                                    info.name, name, known.empty() ? "none" : fmt::format("{}", fmt::join(known, ", "))));
    }
    if (!(value >= option->min && value <= option->max)) {
      throw ConfigError::field("--decoder-option", name, formatValue(value),
                               fmt::format("{} .. {} ({})", formatValue(option->min), formatValue(option->max),
                                           option->meaning));
    }
  }
}

}  // namespace

void VectorNetConfig::validate() const {
  auto require = [](bool ok, const char* field, double value, const char* constraint) {
    if (!ok) throw ConfigError::field("model configuration", field, formatValue(value), constraint);
  };
  require(hidden >= 1 && hidden <= 4096, "hidden", hidden, "1 .. 4096");
  require(subgraphLayers >= 1 && subgraphLayers <= 16, "subgraph_layers", subgraphLayers, "1 .. 16");
  require(globalWidth >= 1 && globalWidth <= 4096, "global_width", globalWidth, "1 .. 4096");
  require(heads >= 1 && globalWidth % heads == 0, "heads", heads, "a divisor of global_width");
  require(decoderHidden >= 1 && decoderHidden <= 8192, "decoder_hidden", decoderHidden, "1 .. 8192");
  require(horizon >= 0 && horizon <= kMaxWindowSteps, "horizon", horizon,
          fmt::format("1 .. {} steps (0: not yet known)", kMaxWindowSteps).c_str());
  require(step == 0.0 || (step >= kMinStep && step <= kMaxStep), "step", step,
          fmt::format("{} .. {} s (0: not yet known)", kMinStep, kMaxStep).c_str());
  require(coordinateScale >= 1e-3 && coordinateScale <= 1e6, "coordinate_scale", coordinateScale, "1e-3 .. 1e6 m");
  validateDecoderOptions(decoderRegistry().find(decoder, "model configuration"), decoderOptions);
  if (!(laneSmoothing > 0.0 && laneSmoothing <= 20.0)) {
    throw ConfigError::field("model configuration", "--lane-smoothing", formatValue(laneSmoothing), "in (0, 20] m");
  }
  const auto& frames = availableFrames();
  if (std::find(frames.begin(), frames.end(), frame) == frames.end()) {
    throw ConfigError::field("model configuration", "--frame", frame, fmt::format("one of {}", fmt::join(frames, ", ")));
  }
}

std::map<std::string, double> parseDecoderOptions(const std::vector<std::string>& items) {
  std::map<std::string, double> options;
  for (const auto& item : items) {
    const auto equals = item.find('=');
    const std::string name = equals == std::string::npos ? "" : item.substr(0, equals);
    const std::string text = equals == std::string::npos ? "" : item.substr(equals + 1);
    double value = 0.0;
    if (text == "true" || text == "on") {
      value = 1.0;
    } else if (text == "false" || text == "off") {
      value = 0.0;
    } else {
      char* end = nullptr;
      value = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0' || !std::isfinite(value)) value = std::nan("");
    }
    if (name.empty() || std::isnan(value)) {
      throw ConfigError::field("command line", "--decoder-option", item, "name=value with a number or true/false");
    }
    if (!options.emplace(name, value).second) {
      throw ConfigError::field("command line", "--decoder-option", item, "each option at most once");
    }
  }
  return options;
}

Mix Mix::parse(const std::string& text) {
  Mix mix;
  if (text.empty()) return mix;
  std::size_t start = 0;
  std::set<std::string> seen;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t equals = item.find('=');
    char* end = nullptr;
    const std::string count = equals == std::string::npos ? "" : item.substr(equals + 1);
    const long long value = std::strtoll(count.c_str(), &end, 10);
    if (equals == std::string::npos || equals == 0 || count.empty() || *end != '\0' || value < 0) {
      throw ConfigError::field("command line", "--mix", text, "label=count[,label=count...] with counts >= 0");
    }
    const std::string label = item.substr(0, equals);
    if (!seen.insert(label).second) {
      throw ConfigError::field("command line", "--mix", text, "each label at most once (" + label + " repeats)");
    }
    mix.counts.emplace_back(label, static_cast<std::size_t>(value));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return mix;
}

std::size_t Mix::total() const {
  std::size_t sum = 0;
  for (const auto& [label, count] : counts) sum += count;
  return sum;
}

std::string Mix::str() const {
  std::string text;
  for (const auto& [label, count] : counts) text += fmt::format("{}{}={}", text.empty() ? "" : ",", label, count);
  return text.empty() ? "all" : text;
}

void TrainOptions::validate() const {
  const std::string where = "command line";
  if (data.empty()) throw ConfigError("--data: no dataset given (dataset files or run folders)");
  if (output.empty()) throw ConfigError("--out: no model file given");
  requireFileOutputPath(output, "--out");
  if (threads < 1 || threads > 256) throw ConfigError::field(where, "--threads", std::to_string(threads), "1 .. 256");
  if (steps < 1 || steps > 100'000'000) throw ConfigError::field(where, "--steps", std::to_string(steps), "1 .. 100000000");
  if (patience < 1) throw ConfigError::field(where, "--patience", std::to_string(patience), ">= 1");
  if (batchSize < 1 || batchSize > 65536) throw ConfigError::field(where, "--batch", std::to_string(batchSize), "1 .. 65536");
  if (!(learningRate > 0.0 && learningRate <= 10.0)) {
    throw ConfigError::field(where, "--lr", formatValue(learningRate), "a rate in (0, 10]");
  }
  if (!(weightDecay >= 0.0 && weightDecay <= 10.0)) {
    throw ConfigError::field(where, "--weight-decay", formatValue(weightDecay), "0 .. 10");
  }
  if (!(validationFraction > 0.0 && validationFraction < 1.0)) {
    throw ConfigError::field(where, "--validation-fraction", formatValue(validationFraction), "in (0, 1)");
  }
  if (!initialModel.empty() && !std::filesystem::is_regular_file(initialModel)) {
    throw ConfigError::field(where, "--init-from", initialModel.string(), "an existing model file");
  }
  config.validate();
}

}  // namespace vsd::model
