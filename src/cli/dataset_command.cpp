#include <fmt/format.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/run_folder/shards.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace vsd::cli {

namespace {

/// A sharded sweep's shards summarised as one dataset (counts added, ranges joined).
vector::DatasetSummary summarize(const std::filesystem::path& path) {
  const auto files = vector::datasetFiles(path);
  vector::DatasetSummary total = vector::summarizeDataset(files.front());
  if (files.size() == 1) return total;
  total.path = fmt::format("{} ({} shards)", path.string(), files.size());
  double vectors = total.vectorsPerSample * static_cast<double>(total.samples);
  double polylines = total.polylinesPerSample * static_cast<double>(total.samples);
  for (std::size_t f = 1; f < files.size(); ++f) {
    const auto part = vector::summarizeDataset(files[f]);
    total.samples += part.samples;
    total.bytes += part.bytes;
    vectors += part.vectorsPerSample * static_cast<double>(part.samples);
    polylines += part.polylinesPerSample * static_cast<double>(part.samples);
    for (const auto& [label, count] : part.samplesPerLabel) total.samplesPerLabel[label] += count;
    for (const auto& source : part.sources) {
      if (std::find(total.sources.begin(), total.sources.end(), source) == total.sources.end()) {
        total.sources.push_back(source);
      }
    }
    for (std::size_t k = 0; k < vector::kFeatures; ++k) {
      total.featureMin[k] = std::min(total.featureMin[k], part.featureMin[k]);
      total.featureMax[k] = std::max(total.featureMax[k], part.featureMax[k]);
    }
  }
  const double samples = std::max<double>(1.0, static_cast<double>(total.samples));
  total.vectorsPerSample = vectors / samples;
  total.polylinesPerSample = polylines / samples;
  return total;
}

/// Unit and meaning of each vector feature (vsd-dataset schema; docs/data-dictionary.md).
struct FeatureEntry {
  const char* name;
  const char* unit;
  const char* meaning;
};
constexpr FeatureEntry kFeatureDictionary[] = {
    {"x_start", "m", "start of the vector, scenario frame (generated roads: x along the road)"},
    {"y_start", "m", "start of the vector, scenario frame (lateral)"},
    {"x_end", "m", "end of the vector"},
    {"y_end", "m", "end of the vector"},
    {"object_type", "-", "1 lane boundary, 2 vehicle, 3 Ego"},
    {"polyline_id", "-", "index of the vector's polyline within its sample"},
    {"timestamp", "s", "time of the vector's end after t0 (lane boundaries: 0)"},
};
static_assert(std::size(kFeatureDictionary) == vector::kFeatures, "one dictionary entry per feature");

/// A run's inputs (unit, description), from the scenario file its manifest names (empty if unknown).
std::map<std::string, scenario::InputSpec> inputSpecs(const std::filesystem::path& given) {
  std::map<std::string, scenario::InputSpec> units;
  try {
    if (!std::filesystem::is_directory(given)) return units;
    const auto manifest = nlohmann::json::parse(readTextFile(given / "manifest.json"));
    const auto logical = scenario::loadLogicalScenario(manifest.at("scenario_file").get<std::string>());
    for (const auto& input : logical->inputs) units[input.name] = input;
  } catch (const std::exception&) {
    // A dataset file alone, or a run whose scenario file moved: its units are not known here.
  }
  return units;
}

/// What every column means and its unit: features, inputs, metrics.
std::string dataDictionary(const vector::DatasetSummary& summary, const std::filesystem::path& given) {
  std::string text = "  data dictionary (docs/data-dictionary.md):\n";
  text += fmt::format("    {:<16} {:<6} {}\n", "feature", "unit", "meaning");
  for (const auto& entry : kFeatureDictionary) {
    text += fmt::format("    {:<16} {:<6} {}\n", entry.name, entry.unit, entry.meaning);
  }
  if (!summary.header.inputNames.empty()) {
    const auto specs = inputSpecs(given);
    text += fmt::format("    {:<16} {:<6} {}\n", "input", "unit", "meaning");
    for (const auto& name : summary.header.inputNames) {
      const auto spec = specs.find(name);
      text += fmt::format("    {:<16} {:<6} {}\n", name, spec == specs.end() ? "?" : spec->second.unit,
                          spec == specs.end() ? "an input of the logical scenario (its unit is in the scenario file)"
                                              : spec->second.description);
    }
  }
  if (!summary.header.metricNames.empty()) {
    text += fmt::format("    {:<16} {:<6} {}\n", "metric", "unit", "definition");
    for (const auto& name : summary.header.metricNames) {
      const auto* metric = metrics::findMetric(name);
      text += fmt::format("    {:<16} {:<6} {}\n", name, metric ? metric->unit : "?",
                          metric ? metric->definition : "not in this version's metric registry");
    }
  }
  return text;
}

int showSample(const std::filesystem::path& path, std::size_t sample, const std::filesystem::path& svg) {
  if (!svg.empty()) {
    checkOutput({svg, &output_kinds::sceneDrawing(), "", false, "--svg", "--force", {{"dataset", path}}});
    requireFileOutputPath(svg, "--svg");
  }
  vector::DatasetCollection collection;
  collection.add(path);
  const auto refs = collection.all();
  if (sample >= refs.size()) {
    throw ConfigError::field("command line", "--sample", std::to_string(sample),
                             fmt::format("an index below {} (the dataset's size)", refs.size()));
  }
  const auto& reader = collection.reader(refs[sample].file);
  const auto scene = collection.scene(refs[sample]);
  const auto ego = scene.egoInitialState();
  fmt::print("sample {} of {}: label {}, source {}, Ego '{}', t0 = {} s\n", sample, reader.path().string(), scene.label,
             scene.provenance.source, scene.provenance.egoId, scene.provenance.t0);
  fmt::print("  Ego at ({:.2f}, {:.2f}) m, heading {:.3f} rad, speed {:.2f} m/s; {} polylines, {} vectors\n", ego.x,
             ego.y, ego.heading, ego.speed, scene.polylines.size(), scene.vectorCount());
  const auto& inputs = reader.header().inputNames;
  for (std::size_t i = 0; i < inputs.size() && i < scene.inputs.size(); ++i) {
    fmt::print("  {} = {}\n", inputs[i], scene.inputs[i]);
  }
  static const char* kTypes[] = {"?", "lane boundary", "vehicle", "Ego"};
  for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
    const auto& polyline = scene.polylines[p];
    std::size_t valid = 0;
    for (auto v : polyline.valid) valid += v;
    fmt::print("  polyline {:>3}: {:<13} {:>3} vectors ({} valid)\n", p, kTypes[static_cast<int>(polyline.type)],
               polyline.vectors.size(), valid);
  }
  if (!svg.empty()) {
    writeTextFileAtomically(svg, vector::renderSceneSvg(scene, {},
                                                        fmt::format("{} sample {} ({})", scene.label, sample,
                                                                    reader.path().filename().string())));
    fmt::print("  drawing: {}\n", svg.string());
  }
  return 0;
}

}  // namespace

void addDatasetCommand(CLI::App& app, CommandContext& context) {
  CLI::App* dataset = app.add_subcommand("dataset", "Inspect and check dataset files");
  dataset->require_subcommand(1);

  auto info_path = std::make_shared<std::filesystem::path>();
  CLI::App* info = dataset->add_subcommand("info", "Counts, schema, provenance and feature ranges");
  info->add_option("dataset", *info_path, "Dataset file, run folder or sharded sweep folder")->required();
  info->callback([info_path, &context] {
    context.action = [info_path] {
      const auto summary = summarize(*info_path);
      fmt::print("{}{}", summary.report(), dataDictionary(summary, *info_path));
      return 0;
    };
  });

  auto show_path = std::make_shared<std::filesystem::path>();
  auto sample = std::make_shared<std::size_t>(0);
  auto svg = std::make_shared<std::filesystem::path>();
  CLI::App* show = dataset->add_subcommand("show", "Print one sample and optionally draw it as SVG");
  show->add_option("dataset", *show_path, "Dataset file, run folder or sharded sweep folder")->required();
  addNumber(show, "--sample", *sample, "Sample index")->capture_default_str();
  show->add_option("--svg", *svg, "Write a drawing of the sample here");
  show->callback([=, &context] { context.action = [=] { return showSample(*show_path, *sample, *svg); }; });

  auto validate_paths = std::make_shared<std::vector<std::filesystem::path>>();
  CLI::App* validate = dataset->add_subcommand("validate", "Check every schema invariant; exit 1 on a problem");
  validate->add_option("datasets", *validate_paths, "Dataset files, run folders or sharded sweep folders")->required();
  validate->callback([validate_paths, &context] {
    context.action = [validate_paths] {
      int status = 0;
      for (const auto& given : *validate_paths) {
        // A sharded sweep: every shard's dataset; otherwise the file or run folder as given.
        const auto paths = hasShards(given) ? vector::datasetFiles(given) : std::vector<std::filesystem::path>{given};
        for (const auto& path : paths) {
          const auto result = vector::validateDataset(path);
          if (result.ok()) {
            fmt::print("{}: valid ({} samples)\n", result.path.string(), result.samples);
            continue;
          }
          status = 1;
          fmt::print("{}: INVALID ({} problems)\n", result.path.string(), result.problems.size());
          for (const auto& problem : result.problems) fmt::print("  {}\n", problem);
        }
      }
      return status;
    };
  });
}

}  // namespace vsd::cli
