#include "vsd/model/presets.hpp"

#include <fmt/format.h>

#include "vsd/core/error.hpp"

namespace vsd::model {

const std::vector<ModelPreset>& modelPresets() {
  static const std::vector<ModelPreset> presets = {
      {"recommended",
       "kinematic decoder in the lane frame, acceleration loss, calibrated intervals: the kinematic model of "
       "docs/results.md",
       "kinematic",
       {{"accel_weight", 10.0}, {"calibrate", 1.0}},
       "lane"},
      {"paper", "offsets decoder predicting displacements in the Ego frame: the paper's VectorNet (no_residual)",
       "offsets",
       {{"residual", 0.0}},
       "ego"},
  };
  return presets;
}

const ModelPreset& findModelPreset(const std::string& name, const std::string& where) {
  std::vector<std::string> known;
  for (const auto& preset : modelPresets()) {
    if (preset.name == name) return preset;
    known.push_back(preset.name);
  }
  throw ConfigError(fmt::format("{}: unknown preset '{}' (known: {})", where, name, fmt::join(known, ", ")));
}

void applyPreset(const ModelPreset& preset, const std::map<std::string, double>& given, VectorNetConfig& config) {
  config.decoder = preset.decoder;
  config.frame = preset.frame;
  config.decoderOptions = preset.decoderOptions;
  for (const auto& [name, value] : given) config.decoderOptions[name] = value;
}

}  // namespace vsd::model
