#include <fmt/format.h>

#include <algorithm>
#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/shards.hpp"
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

int showSample(const std::filesystem::path& path, std::size_t sample, const std::filesystem::path& svg) {
  if (!svg.empty()) requireFileOutputPath(svg, "--svg");
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
      fmt::print("{}", summarize(*info_path).report());
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
