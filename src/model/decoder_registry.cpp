// The decoder registry: one entry per decoder. A new built-in decoder adds its file and a
// line in withBuiltins().
#include <fmt/format.h>

#include "decoder.hpp"
#include "decoders/kinematic.hpp"
#include "decoders/offsets.hpp"
#include "vsd/core/error.hpp"

namespace vsd::model {

DecoderRegistry DecoderRegistry::withBuiltins() {
  DecoderRegistry registry;
  registry.add(offsetsDecoderEntry());
  registry.add(kinematicDecoderEntry());
  return registry;
}

std::shared_ptr<const DecoderRegistry> builtinDecoders() {
  // Const and built from withBuiltins(): a shared default, not a list anyone can add to.
  static const auto builtins = std::make_shared<const DecoderRegistry>(DecoderRegistry::withBuiltins());
  return builtins;
}

void DecoderRegistry::add(DecoderEntry entry) {
  if (entry.info.name.empty() || !entry.create) throw ConfigError("a decoder entry needs a name and a factory");
  if (contains(entry.info.name)) {
    throw ConfigError(fmt::format("decoder '{}' is registered twice", entry.info.name));
  }
  entries_.push_back(std::make_shared<const DecoderEntry>(std::move(entry)));
}

std::vector<DecoderInfo> DecoderRegistry::available() const {
  std::vector<DecoderInfo> infos;
  for (const auto& entry : entries_) infos.push_back(entry->info);
  return infos;
}

bool DecoderRegistry::contains(const std::string& name) const {
  for (const auto& entry : entries_) {
    if (entry->info.name == name) return true;
  }
  return false;
}

const DecoderEntry& DecoderRegistry::entry(const std::string& name, const std::string& where) const {
  std::vector<std::string> known;
  for (const auto& entry : entries_) {
    if (entry->info.name == name) return *entry;
    known.push_back(entry->info.name);
  }
  throw ConfigError(fmt::format("{}: unknown decoder '{}' (known: {})", where, name, fmt::join(known, ", ")));
}

const DecoderInfo& DecoderRegistry::find(const std::string& name, const std::string& where) const {
  return entry(name, where).info;
}

std::unique_ptr<Decoder> makeDecoder(const VectorNetConfig& config) {
  return config.decoderRegistry().entry(config.decoder, "model configuration").create(config);
}

}  // namespace vsd::model
