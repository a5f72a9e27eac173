// The decoder registry: one entry per decoder. A new decoder adds its file and a line here.
#include <fmt/format.h>

#include "decoder.hpp"
#include "decoders/kinematic.hpp"
#include "decoders/offsets.hpp"
#include "vsd/core/error.hpp"

namespace vsd::model {

const std::vector<DecoderEntry>& decoderRegistry() {
  static const std::vector<DecoderEntry> kEntries = {
      offsetsDecoderEntry(),
      kinematicDecoderEntry(),
  };
  return kEntries;
}

const std::vector<DecoderInfo>& availableDecoders() {
  static const std::vector<DecoderInfo> kInfos = [] {
    std::vector<DecoderInfo> infos;
    for (const auto& entry : decoderRegistry()) infos.push_back(entry.info);
    return infos;
  }();
  return kInfos;
}

const DecoderInfo& findDecoder(const std::string& name, const std::string& where) {
  std::vector<std::string> known;
  for (const auto& info : availableDecoders()) {
    if (info.name == name) return info;
    known.push_back(info.name);
  }
  throw ConfigError(fmt::format("{}: unknown decoder '{}' (known: {})", where, name, fmt::join(known, ", ")));
}

std::unique_ptr<Decoder> makeDecoder(const VectorNetConfig& config) {
  for (const auto& entry : decoderRegistry()) {
    if (entry.info.name == config.decoder) return entry.create(config);
  }
  findDecoder(config.decoder, "model configuration");  // throws with the list
  return nullptr;
}

}  // namespace vsd::model
