#include "spec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/options.hpp"
#include "vsd/model/predictor.hpp"
#include "vsd/model/presets.hpp"
#include "vsd/scenario/yaml_reader.hpp"

namespace fs = std::filesystem;

namespace vsd::experiment {

const Source& Spec::source(const std::string& label) const {
  for (const auto& source : sources) {
    if (source.label == label) return source;
  }
  throw ConfigError(fmt::format("{}: no functional scenario '{}'", file.string(), label));
}

bool ModelSpec::trains(int row) const {
  return std::find(rows.begin(), rows.end(), row) != rows.end();
}

const char* heldOutTrainingId(HeldOutTraining training) {
  switch (training) {
    case HeldOutTraining::Others: return "others";
    case HeldOutTraining::OthersAndFewOwn: return "others_and_few_own";
    case HeldOutTraining::FewOwn: return "few_own";
    case HeldOutTraining::AllOwn: return "all_own";
  }
  return "?";
}

const AdeSpec& Spec::row(int number) const {
  for (const auto& row : ade) {
    if (row.row == number) return row;
  }
  throw ConfigError(fmt::format("{}: no ade row {}", file.string(), number));
}

namespace {

/// "file:line" of a node, for messages that name the field themselves.
std::string lineOf(const fs::path& file, const YAML::Node& node) {
  return node.Mark().line >= 0 ? fmt::format("{}:{}", file.string(), node.Mark().line + 1) : file.string();
}

/// A list of ade row numbers, each checked to exist.
std::vector<int> rowList(const scenario::YamlReader& reader, const YAML::Node& node, const std::string& field,
                         const Spec& spec) {
  if (!node.IsSequence()) reader.fail(node, field, "expected a list of ade row numbers, e.g. [3, 4]");
  std::vector<int> rows;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string item = fmt::format("{}[{}]", field, i);
    const double value = reader.number(node[i], item);
    const bool known = std::any_of(spec.ade.begin(), spec.ade.end(), [&](const AdeSpec& a) { return a.row == value; });
    if (!known) reader.fail(node[i], item, fmt::format("no ade row {}", formatNumber(value)));
    rows.push_back(static_cast<int>(value));
  }
  return rows;
}

std::vector<int> allRows(const Spec& spec) {
  std::vector<int> rows;
  for (const auto& row : spec.ade) rows.push_back(row.row);
  return rows;
}

ModelSpec parseModel(const scenario::YamlReader& reader, const YAML::Node& node, const std::string& field,
                     const Spec& spec) {
  reader.checkKeys(node, field, {"name", "preset", "decoder", "frame", "options", "rows", "seeds"});
  ModelSpec model;
  if (!node["name"]) reader.fail(node, field, "missing 'name' (names its rows and cache folders)");
  model.name = reader.scalar(node["name"], field + ".name");
  // It names the model's cache folders.
  requireSafeName(model.name, lineOf(spec.file, node["name"]), field + ".name");
  if (model::Predictor::isBuiltin(model.name)) {
    reader.fail(node["name"], field + ".name", fmt::format("'{}' is a predictor's name (cv, ca): choose another", model.name));
  }
  if (node["decoder"]) model.decoder = reader.scalar(node["decoder"], field + ".decoder");
  if (node["frame"]) model.frame = reader.scalar(node["frame"], field + ".frame");
  if (const auto options = node["options"]) {
    reader.requireMap(options, field + ".options");
    for (const auto& entry : options) {
      const auto key = entry.first.as<std::string>();
      model.options[key] = reader.number(entry.second, field + ".options." + key);
    }
  }
  model::VectorNetConfig config;
  config.decoder = model.decoder;
  config.decoderOptions = model.options;
  config.frame = model.frame;
  if (node["preset"]) {
    // The configuration `train --preset` gives; options add to it, decoder and frame are its own.
    for (const char* key : {"decoder", "frame"}) {
      if (node[key]) reader.fail(node[key], field + "." + key, "given with a preset, which sets it: give one or the other");
    }
    try {
      model::applyPreset(model::findModelPreset(reader.scalar(node["preset"], field + ".preset"), field + ".preset"),
                         model.options, config);
    } catch (const ConfigError& error) {
      reader.fail(node["preset"], field + ".preset", error.what());
    }
    model.decoder = config.decoder;
    model.frame = config.frame;
    model.options = config.decoderOptions;
  }
  try {
    config.validate();
  } catch (const ConfigError& error) {
    reader.fail(node, field, error.what());
  }
  model.rows = node["rows"] ? rowList(reader, node["rows"], field + ".rows", spec) : allRows(spec);
  if (node["seeds"]) model.seeds = reader.integer(node, "seeds", field + ".seeds", 1, 1, 100);
  return model;
}

/// `models`, `seeds` and `predictors`: how each ade row is trained and what else is a row.
void parseModels(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  if (const auto models = root["models"]) {
    if (!models.IsSequence() || models.size() == 0) reader.fail(models, "models", "expected a non-empty list of models");
    for (std::size_t i = 0; i < models.size(); ++i) {
      if (i == 0 && models[i]["rows"]) {
        reader.fail(models[i]["rows"], "models[0].rows",
                    "the first model is the main one and trains every row (findings, MAE and figures use it)");
      }
      auto model = parseModel(reader, models[i], fmt::format("models[{}]", i), spec);
      for (const auto& other : spec.models) {
        if (other.name == model.name) {
          reader.fail(models[i]["name"], fmt::format("models[{}].name", i), fmt::format("'{}' appears twice", model.name));
        }
      }
      spec.models.push_back(std::move(model));
    }
  } else {
    ModelSpec model;
    model.name = "offsets";
    model.rows = allRows(spec);
    spec.models.push_back(model);
  }
  if (const auto seeds = root["seeds"]) {
    reader.checkKeys(seeds, "seeds", {"count", "rows"});
    spec.seedCount = reader.integer(seeds, "count", "seeds.count", 1, 1);
    spec.seedRows = seeds["rows"] ? rowList(reader, seeds["rows"], "seeds.rows", spec) : allRows(spec);
  }
  if (const auto predictors = root["predictors"]) {
    if (!predictors.IsSequence()) reader.fail(predictors, "predictors", "expected a list, e.g. [cv, ca]");
    for (std::size_t i = 0; i < predictors.size(); ++i) {
      const std::string field = fmt::format("predictors[{}]", i);
      const auto name = reader.scalar(predictors[i], field);
      if (!model::Predictor::isBuiltin(name)) {
        reader.fail(predictors[i], field, fmt::format("unknown predictor '{}' (known: cv, ca)", name));
      }
      spec.predictors.push_back(name);
    }
  }
}

/// In --quick, extra seeds and extra models train only the rows of `quick.repeat_rows`, and a
/// model's own `seeds` is one.
/// A model none of whose rows is repeated trains nothing there.
void restrictRepeats(std::vector<int>& rows, const std::vector<int>& allowed) {
  rows.erase(std::remove_if(rows.begin(), rows.end(),
                            [&](int row) { return std::find(allowed.begin(), allowed.end(), row) == allowed.end(); }),
             rows.end());
}

void applyQuickSizes(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  {
    const auto q = root["quick"];
    if (!q) reader.fail(root, "quick", "missing: --quick needs the spec's small sizes");
    reader.checkKeys(q, "quick", {"train_samples", "test_samples", "mix_scale", "steps", "mae_samples", "bnn_epochs", "trees",
                                  "repeat_rows"});
    spec.trainSamples = static_cast<std::uint64_t>(reader.integer(q, "train_samples", "quick.train_samples", 300, 2));
    spec.testSamples = static_cast<std::uint64_t>(reader.integer(q, "test_samples", "quick.test_samples", 300, 1));
    const double scale = reader.number(q, "mix_scale", "quick.mix_scale", 0.1);
    auto scaled = [&](std::size_t count) {
      if (count > 0) count = std::max<std::size_t>(10, static_cast<std::size_t>(std::lround(static_cast<double>(count) * scale)));
      return std::min<std::size_t>(count, spec.trainSamples);
    };
    for (auto& row : spec.ade) {
      for (auto& [label, count] : row.mix) count = scaled(count);
    }
    auto& study = spec.leaveOneOut;
    for (auto* count : {&study.others, &study.fewShot, &study.alone}) *count = scaled(*count);
    spec.steps = reader.integer(q, "steps", "quick.steps", 500, 1);
    spec.maeSamples = static_cast<std::size_t>(reader.integer(q, "mae_samples", "quick.mae_samples", 200, 2));
    spec.bnn.epochs = reader.integer(q, "bnn_epochs", "quick.bnn_epochs", 80, 1);
    spec.extraTrees.trees = reader.integer(q, "trees", "quick.trees", 30, 1);
    std::vector<int> repeat_rows;
    if (const auto rows = q["repeat_rows"]) repeat_rows = rowList(reader, rows, "quick.repeat_rows", spec);
    restrictRepeats(spec.seedRows, repeat_rows);
    for (std::size_t i = 1; i < spec.models.size(); ++i) restrictRepeats(spec.models[i].rows, repeat_rows);
    // A model's own seeds are the full run's claim; the main model's repeated rows already
    // take the several-seeds path here.
    for (auto& model : spec.models) model.seeds = std::min(model.seeds, 1);
  }
}

/// The spec's header: schema, name (its results folder) and seed.
void parseHeader(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  if (root["schema"] && reader.scalar(root["schema"], "schema") != "vsd-experiment/1") {
    throw ConfigError::field(reader.where(root["schema"], "schema"), "schema", reader.scalar(root["schema"], "schema"),
                             "vsd-experiment/1");
  }
  if (!root["name"]) reader.fail(root, "name", "missing (the results' folder name)");
  spec.name = reader.scalar(root["name"], "name");
  // It becomes the results folder results/<name>: one plain name, never ../../elsewhere.
  requireSafeName(spec.name, lineOf(spec.file, root["name"]), "name");
  spec.seed = static_cast<std::uint64_t>(reader.integer(root, "seed", "seed", 1, 0));
}

/// One functional scenario: a logical scenario to simulate, or two existing run folders.
Source parseSource(const scenario::YamlReader& reader, const YAML::Node& label_node, const YAML::Node& value, const Spec& spec) {
  const fs::path base = spec.file.parent_path();
  auto resolve = [&](const fs::path& path) { return path.is_absolute() ? path : base / path; };
  Source source;
  source.label = label_node.as<std::string>();
  const std::string field = "scenarios." + source.label;
  requireSafeName(source.label, lineOf(spec.file, label_node), field);  // it names cache folders
  reader.checkKeys(value, field, {"scenario", "train", "test"});
  if (value["scenario"]) {
    source.scenario = resolve(reader.scalar(value["scenario"], field + ".scenario"));
    if (!fs::is_regular_file(source.scenario)) {
      reader.fail(value["scenario"], field + ".scenario",
                  fmt::format("'{}' does not exist (a logical scenario file)", source.scenario.string()));
    }
  } else if (value["train"] && value["test"]) {
    source.trainRun = resolve(reader.scalar(value["train"], field + ".train"));
    source.testRun = resolve(reader.scalar(value["test"], field + ".test"));
    for (const auto& [path, key] : {std::pair{source.trainRun, "train"}, std::pair{source.testRun, "test"}}) {
      for (const char* needed : {"dataset.h5", "concrete.csv"}) {
        if (!fs::is_regular_file(path / needed)) {
          reader.fail(value[key], field + "." + key,
                      fmt::format("'{}' is not a run folder of vsd-sumo run (no {})", path.string(), needed));
        }
      }
    }
  } else {
    reader.fail(value, field, "needs 'scenario' (to simulate) or 'train' and 'test' (existing runs)");
  }
  return source;
}

void parseSources(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  const auto scenarios = root["scenarios"];
  if (!scenarios) reader.fail(root, "scenarios", "missing (functional scenarios by label)");
  reader.requireMap(scenarios, "scenarios");
  for (const auto& entry : scenarios) spec.sources.push_back(parseSource(reader, entry.first, entry.second, spec));
}

/// `data` (sample counts and seeds of the runs) and `training` (the optimiser's settings).
void parseDataAndTraining(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  if (const auto data = root["data"]) {
    reader.checkKeys(data, "data", {"train_samples", "test_samples", "train_seed", "test_seed", "jobs"});
    spec.trainSamples = static_cast<std::uint64_t>(reader.integer(data, "train_samples", "data.train_samples", 3000, 2));
    spec.testSamples = static_cast<std::uint64_t>(reader.integer(data, "test_samples", "data.test_samples", 10000, 1));
    spec.trainSeed = static_cast<std::uint64_t>(reader.integer(data, "train_seed", "data.train_seed", 1, 0));
    spec.testSeed = static_cast<std::uint64_t>(reader.integer(data, "test_seed", "data.test_seed", 2, 0));
    spec.jobs = reader.integer(data, "jobs", "data.jobs", 2, 1);
  }
  if (const auto training = root["training"]) {
    reader.checkKeys(training, "training", {"steps", "batch", "learning_rate", "threads", "parallel"});
    spec.steps = reader.integer(training, "steps", "training.steps", spec.steps, 1);
    spec.batch = reader.integer(training, "batch", "training.batch", spec.batch, 1);
    spec.learningRate = reader.number(training, "learning_rate", "training.learning_rate", spec.learningRate);
    spec.threads = reader.integer(training, "threads", "training.threads", spec.threads, 1, 256);
    spec.parallel = reader.integer(training, "parallel", "training.parallel", spec.parallel, 1, 64);
  }
}

void requireLabel(const scenario::YamlReader& reader, const Spec& spec, const YAML::Node& node, const std::string& field,
                  const std::string& label) {
  for (const auto& source : spec.sources) {
    if (source.label == label) return;
  }
  std::vector<std::string> known;
  for (const auto& source : spec.sources) known.push_back(source.label);
  reader.fail(node, field, fmt::format("unknown functional scenario '{}' (defined under scenarios: {})", label,
                                       fmt::join(known, ", ")));
}

/// A map from functional-scenario labels to counts (>= 0).
std::vector<std::pair<std::string, std::size_t>> labelledCounts(const scenario::YamlReader& reader, const Spec& spec,
                                                                const YAML::Node& node, const std::string& field) {
  std::vector<std::pair<std::string, std::size_t>> counts;
  reader.requireMap(node, field);
  for (const auto& entry : node) {
    const auto label = entry.first.as<std::string>();
    requireLabel(reader, spec, entry.first, field + "." + label, label);
    counts.emplace_back(label, static_cast<std::size_t>(reader.integer(node, label, field + "." + label, 0, 0)));
  }
  return counts;
}

/// A map from names to numbers (the paper's figures to compare with).
std::map<std::string, double> labelledNumbers(const scenario::YamlReader& reader, const YAML::Node& node,
                                              const std::string& field) {
  std::map<std::string, double> numbers;
  reader.requireMap(node, field);
  for (const auto& entry : node) {
    const auto key = entry.first.as<std::string>();
    numbers[key] = reader.number(entry.second, field + "." + key);
  }
  return numbers;
}

void requireRow(const scenario::YamlReader& reader, const Spec& spec, const YAML::Node& node, const std::string& field,
                int number) {
  for (const auto& row : spec.ade) {
    if (row.row == number) return;
  }
  reader.fail(node, field, fmt::format("no ade row {}", number));
}

/// `ade`: the training mixes, one row each, numbered uniquely.
void parseAdeRows(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  const auto ade = root["ade"];
  if (!ade && root["leave_one_out"]) return;  // a spec of the leave-one-out study alone
  if (!ade || !ade.IsSequence()) reader.fail(root, "ade", "expected a list of training mixes (or a leave_one_out section)");
  std::set<int> rows;
  for (std::size_t i = 0; i < ade.size(); ++i) {
    const std::string field = fmt::format("ade[{}]", i);
    reader.checkKeys(ade[i], field, {"row", "mix", "paper"});
    AdeSpec row;
    row.row = reader.integer(ade[i], "row", field + ".row", static_cast<int>(i) + 1, 1);
    if (!rows.insert(row.row).second) reader.fail(ade[i], field + ".row", fmt::format("row {} appears twice", row.row));
    if (!ade[i]["mix"]) reader.fail(ade[i], field, "missing 'mix'");
    row.mix = labelledCounts(reader, spec, ade[i]["mix"], field + ".mix");
    for (const auto& [label, count] : row.mix) {
      if (!spec.sources.empty() && spec.source(label).scenario.empty()) continue;  // existing runs: checked at training
      if (count > spec.trainSamples && !spec.quick) {
        reader.fail(ade[i]["mix"], field + ".mix." + label,
                    fmt::format("{} samples, but data.train_samples is {}", count, spec.trainSamples));
      }
    }
    if (ade[i]["paper"]) row.paper = labelledNumbers(reader, ade[i]["paper"], field + ".paper");
    spec.ade.push_back(row);
  }
}

/// A list of functional-scenario labels, each defined under `scenarios`.
std::vector<std::string> labelList(const scenario::YamlReader& reader, const Spec& spec, const YAML::Node& node,
                                   const std::string& field) {
  if (!node.IsSequence()) reader.fail(node, field, "expected a list of functional scenarios, e.g. [acc, lk]");
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string item = fmt::format("{}[{}]", field, i);
    const auto label = reader.scalar(node[i], item);
    requireLabel(reader, spec, node[i], item, label);
    if (std::find(labels.begin(), labels.end(), label) != labels.end()) {
      reader.fail(node[i], item, fmt::format("'{}' appears twice", label));
    }
    labels.push_back(label);
  }
  return labels;
}

/// The four rows of one held-out functional scenario (HeldOutTraining), numbered from `first`.
void addHeldOutRows(const LeaveOneOutSpec& study, const std::vector<Source>& sources, const std::string& held_out,
                    int first, Spec& spec) {
  for (const auto training : kHeldOutTrainings) {
    AdeSpec row;
    row.row = first++;
    row.heldOut = held_out;
    row.training = training;
    const bool others = training == HeldOutTraining::Others || training == HeldOutTraining::OthersAndFewOwn;
    if (others) {
      for (const auto& source : sources) {
        if (source.label != held_out) row.mix.emplace_back(source.label, study.others);
      }
    }
    if (training == HeldOutTraining::OthersAndFewOwn || training == HeldOutTraining::FewOwn) {
      row.mix.emplace_back(held_out, study.fewShot);
    }
    if (training == HeldOutTraining::AllOwn) row.mix.emplace_back(held_out, study.alone);
    spec.ade.push_back(std::move(row));
  }
}

/// `leave_one_out`: the study's settings, expanded into four ade rows per held-out scenario.
void parseLeaveOneOut(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  const auto node = root["leave_one_out"];
  if (!node) return;
  const std::string field = "leave_one_out";
  reader.checkKeys(node, field, {"held_out", "context", "others", "few_shot", "alone", "metrics"});
  auto& study = spec.leaveOneOut;
  if (node["context"]) study.context = labelList(reader, spec, node["context"], field + ".context");
  if (node["held_out"]) {
    study.heldOut = labelList(reader, spec, node["held_out"], field + ".held_out");
    for (std::size_t i = 0; i < study.heldOut.size(); ++i) {
      if (std::find(study.context.begin(), study.context.end(), study.heldOut[i]) != study.context.end()) {
        reader.fail(node["held_out"][i], fmt::format("{}.held_out[{}]", field, i),
                    fmt::format("'{}' is in leave_one_out.context (always trained on, never held out)", study.heldOut[i]));
      }
    }
  } else {
    for (const auto& source : spec.sources) {
      if (std::find(study.context.begin(), study.context.end(), source.label) == study.context.end()) {
        study.heldOut.push_back(source.label);
      }
    }
  }
  if (study.heldOut.empty()) reader.fail(node, field, "no functional scenario left to hold out (all are context)");
  if (spec.sources.size() < 2) reader.fail(node, field, "needs at least two functional scenarios under scenarios");
  const auto limit = static_cast<int>(spec.trainSamples);
  // Every count draws from a functional scenario's training pool (data.train_samples).
  auto count = [&](const char* key, int fallback, int minimum) {
    return static_cast<std::size_t>(
        reader.integer(node, key, field + "." + key, std::min(fallback, limit), minimum, limit));
  };
  study.others = count("others", 1000, 1);
  study.fewShot = count("few_shot", 200, 2);
  study.alone = count("alone", 2000, 2);
  if (study.alone <= study.fewShot) {
    reader.fail(node["alone"] ? node["alone"] : node, field + ".alone",
                fmt::format("{} is not more than few_shot ({}): the reference trains on more own samples",
                            study.alone, study.fewShot));
  }
  if (const auto metrics = node["metrics"]) {
    if (!metrics.IsSequence()) reader.fail(metrics, field + ".metrics", "expected a list of metric names, e.g. [d_min]");
    for (std::size_t i = 0; i < metrics.size(); ++i) {
      const std::string item = fmt::format("{}.metrics[{}]", field, i);
      const auto name = reader.scalar(metrics[i], item);
      if (!metrics::findMetric(name)) reader.fail(metrics[i], item, fmt::format("unknown metric '{}'", name));
      study.metrics.push_back(name);
    }
  }
  for (std::size_t i = 0; i < study.heldOut.size(); ++i) {
    addHeldOutRows(study, spec.sources, study.heldOut[i], kFirstHeldOutRow + 10 * static_cast<int>(i), spec);
  }
}

/// `mae.metrics`: per functional scenario, the metrics whose MAE is reported.
void parseMaeMetrics(const scenario::YamlReader& reader, const YAML::Node& metrics, Spec& spec) {
  reader.requireMap(metrics, "mae.metrics");
  for (const auto& by_label : metrics) {
    const auto label = by_label.first.as<std::string>();
    requireLabel(reader, spec, by_label.first, "mae.metrics." + label, label);
    if (!spec.vectornetRows.count(label)) {
      reader.fail(by_label.first, "mae.metrics." + label, "has no entry in mae.vectornet_rows");
    }
    reader.requireMap(by_label.second, "mae.metrics." + label);
    for (const auto& by_metric : by_label.second) {
      const auto metric = by_metric.first.as<std::string>();
      const std::string field = "mae.metrics." + label + "." + metric;
      if (!metrics::findMetric(metric)) reader.fail(by_metric.first, field, fmt::format("unknown metric '{}'", metric));
      MaeMetricSpec item{label, metric, {}};
      if (by_metric.second && by_metric.second.IsMap()) item.paper = labelledNumbers(reader, by_metric.second, field);
      spec.maeMetrics.push_back(item);
    }
  }
}

/// `mae.extra_trees` and `mae.bnn`: the baselines' settings.
void parseBaselines(const scenario::YamlReader& reader, const YAML::Node& mae, Spec& spec) {
  if (const auto trees = mae["extra_trees"]) {
    reader.checkKeys(trees, "mae.extra_trees", {"trees", "max_features", "min_samples_split"});
    spec.extraTrees.trees = reader.integer(trees, "trees", "mae.extra_trees.trees", 100, 1);
    spec.extraTrees.maxFeatures = reader.number(trees, "max_features", "mae.extra_trees.max_features", 1.0);
    spec.extraTrees.minSamplesSplit = reader.integer(trees, "min_samples_split", "mae.extra_trees.min_samples_split", 2, 2);
  }
  if (const auto bnn = mae["bnn"]) {
    reader.checkKeys(bnn, "mae.bnn", {"hidden", "layers", "epochs"});
    spec.bnn.hidden = reader.integer(bnn, "hidden", "mae.bnn.hidden", spec.bnn.hidden, 1);
    spec.bnn.layers = reader.integer(bnn, "layers", "mae.bnn.layers", spec.bnn.layers, 1);
    spec.bnn.epochs = reader.integer(bnn, "epochs", "mae.bnn.epochs", spec.bnn.epochs, 1);
  }
}

/// `mae`: the metric-MAE comparison of VectorNet and the baselines.
void parseMae(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  if (const auto mae = root["mae"]) {
    reader.checkKeys(mae, "mae", {"samples", "draws", "vectornet_rows", "metrics", "extra_trees", "bnn"});
    spec.maeSamples = static_cast<std::size_t>(reader.integer(mae, "samples", "mae.samples", 2000, 2));
    spec.maeDraws = reader.integer(mae, "draws", "mae.draws", spec.maeDraws, 2, 1000);
    if (const auto rows_node = mae["vectornet_rows"]) {
      for (const auto& [label, row] : labelledCounts(reader, spec, rows_node, "mae.vectornet_rows")) {
        requireRow(reader, spec, rows_node[label], "mae.vectornet_rows." + label, static_cast<int>(row));
        spec.vectornetRows[label] = static_cast<int>(row);
      }
    }
    if (const auto metrics = mae["metrics"]) parseMaeMetrics(reader, metrics, spec);
    parseBaselines(reader, mae, spec);
  }
  spec.extraTrees.seed = spec.bnn.seed = spec.seed;
}

/// `figures`: the scenes drawn, each from one ade row's model.
void parseFigures(const scenario::YamlReader& reader, const YAML::Node& root, Spec& spec) {
  const auto figures = root["figures"];
  if (!figures) return;
  for (std::size_t i = 0; i < figures.size(); ++i) {
    const std::string field = fmt::format("figures[{}]", i);
    reader.checkKeys(figures[i], field, {"name", "row", "title"});
    FigureSpec figure;
    if (!figures[i]["name"] || !figures[i]["row"]) reader.fail(figures[i], field, "needs 'name' and 'row'");
    figure.name = reader.scalar(figures[i]["name"], field + ".name");
    requireSafeName(figure.name, lineOf(spec.file, figures[i]["name"]), field + ".name");
    figure.row = reader.integer(figures[i], "row", field + ".row", 0, 1);
    requireRow(reader, spec, figures[i]["row"], field + ".row", figure.row);
    if (figures[i]["title"]) figure.title = reader.scalar(figures[i]["title"], field + ".title");
    spec.figures.push_back(figure);
  }
}

}  // namespace

Spec parseSpec(const fs::path& file, bool quick) {
  std::string text;
  try {
    text = readTextFile(file, read_limits::kSpec);
  } catch (const IoError& error) {
    throw ConfigError(error.what());
  }
  const scenario::YamlReader reader(file.string());
  const auto root = scenario::loadYaml(text, file.string());
  reader.checkKeys(root, "", {"schema", "name", "seed", "scenarios", "data", "training", "ade", "models", "seeds", "predictors", "mae",
                          "figures", "quick", "leave_one_out"});
  Spec spec;
  spec.file = file;
  spec.quick = quick;
  parseHeader(reader, root, spec);
  parseSources(reader, root, spec);
  parseDataAndTraining(reader, root, spec);
  parseAdeRows(reader, root, spec);
  parseLeaveOneOut(reader, root, spec);
  parseModels(reader, root, spec);
  parseMae(reader, root, spec);
  parseFigures(reader, root, spec);
  if (quick) applyQuickSizes(reader, root, spec);
  return spec;
}

}  // namespace vsd::experiment
