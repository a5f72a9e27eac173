#pragma once
// Named model configurations (issue 26: the configuration the docs report is one name away).
// `train --preset recommended` trains what docs/results.md reports for the kinematic model;
// `bench model` and the experiment spec (`preset:`) take the same names, so a benchmark, an
// experiment and a user's training of a preset are the same configuration.
//
// Adding a preset: one entry in src/model/presets.cpp.

#include <map>
#include <string>
#include <vector>

#include "vsd/model/options.hpp"

namespace vsd::model {

struct ModelPreset {
  std::string name;
  std::string description;  ///< one line: what it is and where the docs report it
  std::string decoder;
  std::map<std::string, double> decoderOptions;
  std::string frame;
};

/// Every preset, in a fixed order.
const std::vector<ModelPreset>& modelPresets();
/// Throws ConfigError naming `where` and the known presets.
const ModelPreset& findModelPreset(const std::string& name, const std::string& where);

/// `config` with the preset's decoder, frame and options; `given` decoder options override
/// or add to the preset's (a user's --decoder-option on top of a preset).
void applyPreset(const ModelPreset& preset, const std::map<std::string, double>& given, VectorNetConfig& config);

}  // namespace vsd::model
