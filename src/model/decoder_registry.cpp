// The decoder registry: one entry per decoder. A new decoder adds its file and a line here.
#include <fmt/format.h>

#include "decoder.hpp"
#include "decoders/kinematic.hpp"
#include "decoders/offsets.hpp"
#include "vsd/core/error.hpp"

namespace vsd::model {

namespace {

/// The built-ins (one line each), then what addDecoder() added.
std::vector<DecoderEntry>& entries() {
  static std::vector<DecoderEntry> registered = {
      offsetsDecoderEntry(),
      kinematicDecoderEntry(),
  };
  return registered;
}

/// The public descriptions, in registry order (kept beside the entries).
std::vector<DecoderInfo>& infos() {
  static std::vector<DecoderInfo> described = [] {
    std::vector<DecoderInfo> result;
    for (const auto& entry : entries()) result.push_back(entry.info);
    return result;
  }();
  return described;
}

}  // namespace

const std::vector<DecoderEntry>& decoderRegistry() { return entries(); }

void addDecoder(DecoderEntry entry) {
  if (entry.info.name.empty() || !entry.create) throw ConfigError("a decoder entry needs a name and a factory");
  for (const auto& existing : entries()) {
    if (existing.info.name == entry.info.name) {
      throw ConfigError(fmt::format("decoder '{}' is registered twice", entry.info.name));
    }
  }
  infos();  // described before the entry is added, so that it is added to both once
  infos().push_back(entry.info);
  entries().push_back(std::move(entry));
}

const std::vector<DecoderInfo>& availableDecoders() { return infos(); }

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
