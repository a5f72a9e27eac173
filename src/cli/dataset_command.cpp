#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace vsd::cli {

namespace {

int showSample(const std::filesystem::path& path, std::size_t sample, const std::filesystem::path& svg) {
  if (!svg.empty()) requireFileOutputPath(svg, "--svg");
  const vector::DatasetReader reader(vector::resolveDatasetPath(path));
  if (sample >= reader.size()) {
    throw ConfigError::field("command line", "--sample", std::to_string(sample),
                             fmt::format("an index below {} (the dataset's size)", reader.size()));
  }
  const auto scene = reader.scene(sample);
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
  info->add_option("dataset", *info_path, "Dataset file or run folder")->required();
  info->callback([info_path, &context] {
    context.action = [info_path] {
      fmt::print("{}", vector::summarizeDataset(vector::resolveDatasetPath(*info_path)).report());
      return 0;
    };
  });

  auto show_path = std::make_shared<std::filesystem::path>();
  auto sample = std::make_shared<std::size_t>(0);
  auto svg = std::make_shared<std::filesystem::path>();
  CLI::App* show = dataset->add_subcommand("show", "Print one sample and optionally draw it as SVG");
  show->add_option("dataset", *show_path, "Dataset file or run folder")->required();
  addNumber(show, "--sample", *sample, "Sample index")->capture_default_str();
  show->add_option("--svg", *svg, "Write a drawing of the sample here");
  show->callback([=, &context] { context.action = [=] { return showSample(*show_path, *sample, *svg); }; });

  auto validate_paths = std::make_shared<std::vector<std::filesystem::path>>();
  CLI::App* validate = dataset->add_subcommand("validate", "Check every schema invariant; exit 1 on a problem");
  validate->add_option("datasets", *validate_paths, "Dataset files or run folders")->required();
  validate->callback([validate_paths, &context] {
    context.action = [validate_paths] {
      int status = 0;
      for (const auto& path : *validate_paths) {
        const auto result = vector::validateDataset(vector::resolveDatasetPath(path));
        if (result.ok()) {
          fmt::print("{}: valid ({} samples)\n", result.path.string(), result.samples);
          continue;
        }
        status = 1;
        fmt::print("{}: INVALID ({} problems)\n", result.path.string(), result.problems.size());
        for (const auto& problem : result.problems) fmt::print("  {}\n", problem);
      }
      return status;
    };
  });
}

}  // namespace vsd::cli
