// <out>/checkpoint.json: every execution of the finished rounds, written atomically
// after each round. Numbers are stored as exact text (formatNumber), so a resumed
// search refits the same surrogate on the same values and makes the same choices.
// It records what made it (identity(): scenario hash, seed, options), the SHA-256 of
// every round's files in <out>/.rounds/ and a checksum of its own contents, all checked
// when a search resumes, before any work.

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdlib>

#include "search_internal.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::search::detail {

namespace {

constexpr const char* kSchema = "vsd-search-checkpoint/2";
constexpr const char* kChecksumKey = "contents_sha256";
constexpr const char* kRoundFileNames[] = {"traces.h5", "dataset.h5"};

std::string contentsChecksum(nlohmann::json json) {
  json.erase(kChecksumKey);
  return sha256OfString(json.dump());
}

fs::path checkpointPath(const SearchContext& context) { return context.options.outputDir / "checkpoint.json"; }

/// The options a checkpoint's executions depend on; a resume must match every one.
nlohmann::json identity(const SearchContext& context) {
  const auto& o = context.options;
  nlohmann::json json = {{"scenario_sha256", context.scenarioSha256},
          {"criterion", context.criterion->expression()},
          {"surrogate", o.surrogate},
          {"seed", o.seed},
          {"initial", o.initial},
          {"round", o.roundSize},
          {"estimate_share", formatNumber(o.estimateShare)},
          {"pool", o.pool},
          {"diversity", formatNumber(o.diversity)},
          {"trees", o.trees},
          {"bnn_epochs", o.bnnEpochs}};
  if (o.probability != "shifts") json["probability"] = o.probability;  // checkpoints from before it stay valid
  if (o.rankTargets) json["rank_targets"] = true;
  if (!o.reference.empty()) json["reference"] = o.reference;  // absent: searches without one
  if (context.surrogate->learnsFromScenes) {
    nlohmann::json priors = nlohmann::json::array();
    for (const auto& file : context.priors) priors.push_back({{"file", file.string()}, {"sha256", sha256OfFile(file)}});
    json["prior"] = priors;
    json["vectornet_steps"] = o.vectornetSteps;
    json["future_samples"] = o.futureSamples;
    json["threads"] = o.threads;  // training's float rounding depends on the thread layout
  }
  return json;
}

nlohmann::json numbers(const std::vector<double>& values) {
  nlohmann::json list = nlohmann::json::array();
  for (const double value : values) list.push_back(formatNumber(value));
  return list;
}

double parseNumber(const std::string& text) {
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  return std::strtod(text.c_str(), nullptr);
}

std::vector<double> parseNumbers(const nlohmann::json& list) {
  std::vector<double> values;
  for (const auto& item : list) values.push_back(parseNumber(item.get<std::string>()));
  return values;
}

Execution parseExecution(const nlohmann::json& item) {
  Execution execution;
  execution.round = item.at("round").get<std::uint64_t>();
  execution.origin = item.at("origin").get<std::string>();
  execution.sample = item.at("sample").get<std::uint64_t>();
  execution.acquisition = parseNumber(item.at("acquisition").get<std::string>());
  execution.predicted = parseNumber(item.at("predicted").get<std::string>());
  execution.failure = item.at("failure").get<std::string>();
  execution.verdict = item.at("verdict").get<int>();
  execution.inputs = parseNumbers(item.at("inputs"));
  execution.metrics = parseNumbers(item.at("metrics"));
  execution.draws = item.at("draws").get<std::uint64_t>();
  execution.weight = parseNumber(item.at("weight").get<std::string>());
  return execution;
}

void requireSameOptions(const SearchContext& context, const nlohmann::json& stored, const fs::path& path) {
  const nlohmann::json expected = identity(context);
  for (const auto& [key, value] : expected.items()) {
    if (!stored.contains(key) || stored.at(key) != value) {
      throw ConfigError(fmt::format("{}: a search with {} = {} (this one: {}); use another --out or remove the folder",
                                    path.string(), key, stored.contains(key) ? stored.at(key).dump() : "?",
                                    value.dump()));
    }
  }
}

/// Every round's files must be the ones the checkpoint recorded.
std::vector<std::map<std::string, std::string>> checkRoundFiles(const SearchContext& context, const nlohmann::json& list,
                                                                std::uint64_t rounds, const fs::path& path) {
  if (list.size() != rounds) {
    throw DatasetError(fmt::format("{}: lists {} rounds but the files of {}", path.string(), rounds, list.size()));
  }
  std::vector<std::map<std::string, std::string>> hashes;
  for (std::uint64_t round = 0; round < rounds; ++round) {
    std::map<std::string, std::string> files;
    for (const char* name : kRoundFileNames) {
      const fs::path file = roundFile(context, round, name);
      if (!fs::exists(file)) {
        throw DatasetError(fmt::format("{}: missing: the checkpoint lists round {} but its executions' {} are gone "
                                       "(start the search in a new --out folder)",
                                       file.string(), round, name));
      }
      const std::string recorded = list.at(round).at(name).get<std::string>();
      if (sha256OfFile(file) != recorded) {
        throw DatasetError(fmt::format("{}: not the file of round {} that {} records (its SHA-256 differs: another "
                                       "search's, or changed since): start the search in a new --out folder",
                                       file.string(), round, path.filename().string()));
      }
      files[name] = recorded;
    }
    hashes.push_back(std::move(files));
  }
  return hashes;
}

}  // namespace

std::optional<SearchState> readCheckpoint(const SearchContext& context) {
  const fs::path path = checkpointPath(context);
  if (!fs::exists(path)) {
    if (fs::exists(context.options.outputDir / "manifest.json")) {
      throw ConfigError(fmt::format("{}: holds other outputs (a manifest but no search checkpoint); choose an "
                                    "empty --out",
                                    context.options.outputDir.string()));
    }
    return std::nullopt;
  }
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(readTextFile(path, read_limits::kState));
    if (json.at("schema").get<std::string>() != kSchema) {
      throw DatasetError(fmt::format("{}: schema {}, expected {} (written by another vsd-sumo version): start the "
                                     "search in a new --out folder",
                                     path.string(), json.at("schema").dump(), kSchema));
    }
    if (json.at(kChecksumKey).get<std::string>() != contentsChecksum(json)) {
      throw DatasetError(fmt::format("{}: edited after it was written (its {} does not match its contents): start "
                                     "the search in a new --out folder",
                                     path.string(), kChecksumKey));
    }
    requireSameOptions(context, json.at("options"), path);
    SearchState state;
    state.rounds = json.at("rounds").get<std::uint64_t>();
    for (const auto& item : json.at("executions")) state.executions.push_back(parseExecution(item));
    state.roundFileSha256 = checkRoundFiles(context, json.at("round_files"), state.rounds, path);
    return state;
  } catch (const nlohmann::json::exception& error) {
    throw DatasetError(fmt::format("{}: not a search checkpoint ({})", path.string(), error.what()));
  }
}

void writeCheckpoint(const SearchContext& context, SearchState& state) {
  for (std::uint64_t round = state.roundFileSha256.size(); round < state.rounds; ++round) {
    std::map<std::string, std::string> files;
    for (const char* name : kRoundFileNames) files[name] = sha256OfFile(roundFile(context, round, name));
    state.roundFileSha256.push_back(std::move(files));
  }
  nlohmann::json json;
  json["schema"] = kSchema;
  json["options"] = identity(context);
  json["rounds"] = state.rounds;
  nlohmann::json executions = nlohmann::json::array();
  for (const auto& e : state.executions) {
    executions.push_back({{"round", e.round},
                          {"origin", e.origin},
                          {"sample", e.sample},
                          {"acquisition", formatNumber(e.acquisition)},
                          {"predicted", formatNumber(e.predicted)},
                          {"failure", e.failure},
                          {"verdict", e.verdict},
                          {"inputs", numbers(e.inputs)},
                          {"metrics", numbers(e.metrics)},
                          {"draws", e.draws},
                          {"weight", formatNumber(e.weight)}});
  }
  json["executions"] = std::move(executions);
  json["round_files"] = state.roundFileSha256;
  json[kChecksumKey] = contentsChecksum(json);
  writeTextFileAtomically(checkpointPath(context), json.dump() + "\n");
}

}  // namespace vsd::search::detail
