// `vsd-sumo deviations`: reading field data, ranking and grouping, the CSV and the report
// (compare/deviations.hpp; scoring in deviation_scoring.cpp).
#include "vsd/compare/deviations.hpp"

#include "deviation_outputs.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/model/predictor.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/report/deviation_report.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace fs = std::filesystem;

namespace vsd::compare {

namespace {

/// Scenes read and scored at a time (bounds the memory of the sampled futures).
constexpr std::size_t kChunk = 1024;

std::string number(double value, int decimals = 2) {
  if (std::isnan(value)) return "-";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return fmt::format("{:.{}f}", value, decimals);
}

/// "a_min -3.1 m/s^2 below its calibrated 90 % interval [-7.9, -5.2] (p 0.004)".
std::string metricReason(const DeviationResult& result, const SceneDeviation& scene) {
  const auto m = scene.worstMetric;
  const auto& tail = scene.metrics.at(m);
  const bool below = tail.recorded < intervalCentre(result, tail);
  const bool inside = tail.recorded >= tail.p05 && tail.recorded <= tail.p95;
  return fmt::format("{} {} {} {} its calibrated 90 % interval [{}, {}] (p {:.3g})", result.metricNames[m],
                     number(tail.recorded), result.metricUnits[m], inside ? (below ? "in the lower part of" : "in the upper part of")
                                                                           : (below ? "below" : "above"),
                     number(tail.p05), number(tail.p95), tail.p);
}

/// "the recorded path leaves its calibrated 90 % region by a factor 3.1 in squared distance
/// (at 2.4 s: ...)", with the path's p where calibration runs give one.
std::string pathReason(const SceneDeviation& scene, double step) {
  if (std::isnan(scene.regionExcess)) return "";
  return fmt::format("the recorded path {} its calibrated 90 % region {} (at {:.1f} s: {:+.2f} m along, {:+.2f} m "
                     "across the predicted heading{})",
                     scene.regionExcess > 1.0 ? "leaves" : "stays inside",
                     scene.regionExcess > 1.0 ? fmt::format("by a factor {:.1f} in squared distance", scene.regionExcess)
                                              : "throughout",
                     step * scene.regionStep, scene.longitudinal, scene.lateral,
                     std::isnan(scene.pathP) ? "" : fmt::format("; p {:.3g} among the calibration runs' paths", scene.pathP));
}

/// Why a flagged scene is flagged: its smallest p first.
std::string flagReason(const DeviationResult& result, const SceneDeviation& scene) {
  const auto path = pathReason(scene, result.step);
  const auto metric = metricReason(result, scene);
  if (scene.pathWorst) return path + "; " + metric;
  return path.empty() ? metric : metric + "; " + path;
}

/// "<label>: <axis>, <metric> <lower|higher> than predicted" (or "path far from the most likely one").
std::string flagGroup(const DeviationResult& result, const SceneDeviation& scene) {
  if (scene.pathWorst) return fmt::format("{}: {}, path far from the most likely one", scene.label, scene.axis);
  const auto& tail = scene.metrics.at(scene.worstMetric);
  return fmt::format("{}: {}, {} {}", scene.label, scene.axis, result.metricNames[scene.worstMetric],
                     tail.recorded < intervalCentre(result, tail) ? "lower than predicted" : "higher than predicted");
}

}  // namespace

std::vector<std::size_t> rankDeviations(DeviationResult& result) {
  std::vector<std::size_t> flagged;
  for (std::size_t i = 0; i < result.scenes.size(); ++i) {
    auto& scene = result.scenes[i];
    scene.flagged = scene.status == SceneStatus::Scored && scene.p < result.level;
    if (!scene.flagged) continue;
    scene.reason = flagReason(result, scene);
    scene.group = flagGroup(result, scene);
    flagged.push_back(i);
  }
  std::stable_sort(flagged.begin(), flagged.end(), [&](std::size_t a, std::size_t b) {
    const auto& x = result.scenes[a];
    const auto& y = result.scenes[b];
    if (x.p != y.p) return x.p < y.p;
    return x.regionExcess > y.regionExcess;
  });
  return flagged;
}

void DeviationOptions::validate() const {
  if (!(level > 0.0 && level < 1.0)) {
    throw ConfigError::field("command line", "--level", formatValue(level), "a share in (0, 1), e.g. 0.05");
  }
  if (data.empty()) throw ConfigError::field("command line", "--data", "(none)", "field data: dataset files or run folders");
  if (output.empty()) throw ConfigError::field("command line", "--out", "(none)", "a report folder");
  if (threads < 1 || threads > 256) throw ConfigError::field("command line", "--threads", std::to_string(threads), "1 .. 256");
  if (drawn < 0 || drawn > 100) throw ConfigError::field("command line", "--drawn", std::to_string(drawn), "0 .. 100");
}

std::size_t DeviationSummary::scored() const {
  return static_cast<std::size_t>(std::count_if(result.scenes.begin(), result.scenes.end(),
                                                [](const auto& s) { return s.status == SceneStatus::Scored; }));
}

std::size_t DeviationSummary::outOfDistribution() const {
  return static_cast<std::size_t>(std::count_if(result.scenes.begin(), result.scenes.end(), [](const auto& s) {
    return s.status == SceneStatus::OutOfDistribution;
  }));
}

namespace {

/// The field data, opened and checked against the model before any work.
struct Field {
  vector::DatasetCollection collection;
  metrics::Availability available{true, true, true};
  std::vector<std::string> metricNames;  ///< every metric that applies to all files
  std::vector<std::string> inputNames;   ///< the first file's (features when all files share them)
  std::size_t samples = 0;
};

/// What a --data (`flag`) path stands for: a dataset file, a run or sweep folder
/// (vector::datasetFiles), or a folder of dataset files (*.h5, e.g. map exports) in name order.
std::vector<fs::path> fieldFiles(const fs::path& path, const std::string& flag) {
  if (!fs::is_directory(path) || fs::exists(path / "manifest.json") || fs::exists(path / "shards")) return {path};
  std::vector<fs::path> files;
  bool anything = false;
  for (const auto& entry : fs::directory_iterator(path)) {
    anything = anything || entry.path().filename().string().front() != '.';
    if (entry.is_regular_file() && entry.path().extension() == ".h5") files.push_back(entry.path());
  }
  if (!anything) {
    throw DatasetError(fmt::format("{} {}: an empty folder (expected a run folder, a sweep folder or dataset "
                                   "files)",
                                   flag, path.string()));
  }
  if (files.empty()) return {path};  // vector::datasetFiles says what is wrong with it
  std::sort(files.begin(), files.end());
  return files;
}

/// Opens the recorded runs of `paths` (given by `flag`) and checks them against the model.
Field openField(const std::vector<fs::path>& paths, const std::string& flag, const DeviationOptions& options,
                const model::Predictor& predictor) {
  Field field;
  for (const auto& path : paths) {
    for (const auto& file : fieldFiles(path, flag)) field.collection.add(file);
  }
  for (std::size_t f = 0; f < field.collection.files(); ++f) {
    const auto& reader = field.collection.reader(f);
    predictor.checkCompatible(reader.header(), reader.path().string());  // step and horizon
    const auto available = pipeline::sceneAvailability(reader.header().kind);
    field.available.otherVehicles &= available.otherVehicles;
    field.available.egoLane &= available.egoLane;
    field.available.scenarioFrame &= available.scenarioFrame;
    field.samples += reader.size();
  }
  if (field.samples == 0) {
    throw DatasetError(fmt::format("{} {}: no recorded scenes in it", flag, paths.front().string()));
  }
  field.inputNames = field.collection.reader(0).header().inputNames;
  for (std::size_t f = 1; f < field.collection.files(); ++f) {
    if (field.collection.reader(f).header().inputNames != field.inputNames) field.inputNames.clear();
  }
  const auto& stored = field.collection.reader(0).header().metricNames;
  field.metricNames = !options.metrics.empty() ? options.metrics
                      : !stored.empty()        ? stored
                                               : metrics::defaultMetrics(field.available);
  field.metricNames = metrics::MetricSet(field.metricNames, field.available, "--metrics").names();  // checked once
  return field;
}

/// Refuses scenes holding road users of kinds the model never saw (one line: file, sample, kind).
void checkRoadUsers(const vector::VectorizedScene& scene, const model::ModelInfo& info, const std::string& model,
                    const fs::path& file) {
  if (info.roadUsers.empty()) return;  // not recorded by model files of before: see the report's note
  for (const auto& polyline : scene.polylines) {
    if (polyline.type == vector::ObjectType::LaneBoundary) continue;
    const std::string kind = roadUserKind(polyline.roadUser).name;
    if (std::find(info.roadUsers.begin(), info.roadUsers.end(), kind) == info.roadUsers.end()) {
      throw ModelError(fmt::format("{}: sample {} holds a road user of kind '{}', which the model {} never saw (it "
                                   "saw {}): its predictions there mean nothing",
                                   file.string(), scene.sample, kind, model, fmt::join(info.roadUsers, ", ")));
    }
  }
}

/// Reads and scores every scene of `field`, a chunk at a time. With `ranks` (calibration runs), a
/// scene of a trained label they cannot rank stops it before any of its chunk is scored.
void scoreField(const Field& field, const DeviationScorer& scorer, const model::ModelInfo& info,
                const DeviationOptions& options, DeviationResult& result, double& scoring_seconds,
                const RunCalibration* ranks = nullptr) {
  for (std::size_t f = 0; f < field.collection.files(); ++f) {
    const auto& reader = field.collection.reader(f);
    const auto& stored = reader.header().metricNames;
    for (std::size_t first = 0; first < reader.size(); first += kChunk) {
      throwIfInterrupted();
      std::vector<vector::VectorizedScene> scenes;
      for (std::size_t i = first; i < std::min(reader.size(), first + kChunk); ++i) {
        scenes.push_back(reader.scene(i));
        checkRoadUsers(scenes.back(), info, options.model.string(), reader.path());
        if (ranks && scorer.trainedOn(scenes.back().label)) {
          ranks->requireRuns(scenes.back().label, scorer.metricNames().size());
        }
        if (field.inputNames.empty()) scenes.back().inputs.clear();  // files with other inputs: no input features
      }
      const auto start = std::chrono::steady_clock::now();
      auto rows = scorer.score(scenes, stored, reader.path().string());
      scoring_seconds += secondsSince(start);
      for (std::size_t j = 0; j < rows.size(); ++j) {
        rows[j].row = first + j;
        result.scenes.push_back(std::move(rows[j]));
      }
    }
  }
}

/// The calibration runs (--calibration), scored like the field and ranked among per label; nullopt
/// without them. Refuses runs whose scenes hold other information than the field's (another kind).
std::optional<RunCalibration> calibrateOnRuns(const Field& field, const DeviationScorer& scorer,
                                              const model::Predictor& predictor, const DeviationOptions& options) {
  if (options.calibration.empty()) return std::nullopt;
  const Field runs = openField(options.calibration, "--calibration", options, predictor);
  const auto& a = field.available;
  const auto& b = runs.available;
  if (a.otherVehicles != b.otherVehicles || a.egoLane != b.egoLane || a.scenarioFrame != b.scenarioFrame) {
    throw DatasetError(fmt::format("--calibration {}: its scenes hold other information than the field data's (e.g. a "
                                   "map export against generated runs): the scores would not be comparable",
                                   options.calibration.front().string()));
  }
  DeviationResult scored;
  double seconds = 0.0;
  scoreField(runs, scorer, predictor.info(), options, scored, seconds);
  std::vector<std::string> names;
  for (const auto& path : options.calibration) names.push_back(path.string());
  return RunCalibration(scored.scenes, scorer.metricNames().size(), fmt::format("{}", fmt::join(names, " ")),
                        options.level);
}

/// deviations.csv, staged in `folder`.
void writeTable(OutputFolder& folder, const DeviationSummary& summary, const fs::path& output) {
  const auto& result = summary.result;
  {
    std::ofstream stream(folder.stage("deviations.csv"));
    CsvWriter csv(stream);
    csv.writeRow(csvHeader(result));
    std::vector<std::size_t> rank(result.scenes.size(), 0);
    for (std::size_t r = 0; r < summary.ranked.size(); ++r) rank[summary.ranked[r]] = r + 1;
    for (std::size_t i = 0; i < result.scenes.size(); ++i) csv.writeRow(csvRow(result, result.scenes[i], rank[i]));
    stream.flush();
    if (!stream) throw IoError(fmt::format("{}: cannot write", (output / "deviations.csv").string()));
  }
  folder.staged("deviations.csv");
}

/// The scenes of the `drawn` most surprising flagged rows, read again from the field data.
std::vector<vector::VectorizedScene> drawnScenes(const Field& field, const DeviationSummary& summary, int drawn) {
  std::vector<vector::VectorizedScene> scenes;
  for (std::size_t r = 0; r < summary.ranked.size() && r < static_cast<std::size_t>(drawn); ++r) {
    const auto& scene = summary.result.scenes[summary.ranked[r]];
    for (std::size_t f = 0; f < field.collection.files(); ++f) {
      const auto& reader = field.collection.reader(f);
      if (reader.path().string() == scene.source) scenes.push_back(reader.scene(scene.row));
    }
  }
  return scenes;
}

}  // namespace

DeviationSummary findDeviations(const DeviationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.validate();
  refuseDirtyCommittedResults(options.output, options.allowDirty, "--allow-dirty");
  if (!fs::is_regular_file(options.model)) throw ModelError(fmt::format("--model {}: no such file", options.model.string()));
  std::vector<std::pair<std::string, fs::path>> inputs = {{"--model", options.model}};
  std::vector<std::string> names;
  for (const auto& path : options.data) {
    inputs.emplace_back("--data", path);
    names.push_back(path.filename().string());
  }
  for (const auto& path : options.calibration) inputs.emplace_back("--calibration", path);
  const std::string subject = fmt::format("{} with {}", fmt::join(names, ", "), options.model.filename().string());
  checkOutput({options.output, &output_kinds::deviationsFolder(), subject, options.force, "--out", "--force", inputs});
  const model::Predictor predictor(options.model, options.threads);
  const Field field = openField(options.data, "--data", options, predictor);
  const DeviationScorer scorer(predictor, options.model.string(), field.metricNames, field.available, options.seed);

  DeviationSummary summary;
  auto& result = summary.result;
  result.level = options.level;
  result.step = field.collection.reader(0).header().step;
  result.metricNames = scorer.metricNames();
  result.metricUnits = scorer.metricUnits();
  for (const auto& input : field.inputNames) {
    result.featureNames.push_back("input_" + input);
    result.featureUnits.emplace_back();  // the scenario file's unit (docs/data-dictionary.md)
  }
  result.featureNames.push_back("v0_ego");
  result.featureUnits.push_back("m/s");
  if (predictor.info().roadUsers.empty()) {
    summary.warnings.push_back(fmt::format("{} does not record the kinds of road users it trained on (a model file "
                                           "written before they were recorded): scenes of kinds it never saw could "
                                           "not be refused",
                                           options.model.string()));
  }
  for (const auto& warning : summary.warnings) spdlog::warn("{}", warning);
  const auto calibration = calibrateOnRuns(field, scorer, predictor, options);
  scoreField(field, scorer, predictor.info(), options, result, summary.scoringSeconds,
             calibration ? &*calibration : nullptr);
  if (calibration) {
    for (auto& scene : result.scenes) calibration->apply(scene);
    result.calibrationRuns = calibration->runs();
  }
  summary.ranked = rankDeviations(result);
  summary.output = options.output;

  OutputFolder folder(options.output);
  writeTable(folder, summary, options.output);
  const auto drawn = drawnScenes(field, summary, options.drawn);
  std::vector<std::pair<std::string, std::string>> provenance = {
      {"model file", options.model.string()}, {"model SHA-256", sha256OfFile(options.model)}};
  for (const auto& path : options.data) provenance.push_back({"field data", path.string()});
  for (const auto& path : options.calibration) provenance.push_back({"calibration runs", path.string()});
  provenance.push_back({"p-values", calibration ? fmt::format("conformal ranks among {} clean calibration runs",
                                                              result.calibrationRuns)
                                                : std::string("the model's own calibration")});
  provenance.push_back({"level", formatNumber(options.level)});
  provenance.push_back({"sampled futures", fmt::format("{} per scene, seed {}", model::kCalibrationDraws, options.seed)});
  provenance.push_back({"vsd-sumo", toolVersion()});
  provenance.push_back({"command line", options.commandLine});
  provenance.push_back({"written", utcTimestamp()});
  summary.seconds = secondsSince(start);
  folder.stageText("report.html",
                   report::renderDeviationReport(buildReport(summary, drawn, provenance)));
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  manifest["kind"] = "deviations";
  manifest["subject"] = subject;
  for (const auto& [key, value] : provenance) manifest["provenance"][key] = value;
  folder.commit(manifest);
  summary.seconds = secondsSince(start);
  return summary;
}

std::string DeviationSummary::report() const {
  const std::size_t flagged = ranked.size();
  const std::size_t n = scored();
  std::string text = fmt::format("deviations: {} scenes, {} scored, {} flagged at level {:g} ({:.1f} %), {} out of "
                                 "the model's distribution\n",
                                 result.scenes.size(), n, flagged, result.level,
                                 n ? 100.0 * static_cast<double>(flagged) / static_cast<double>(n) : 0.0,
                                 outOfDistribution());
  text += result.calibrationRuns > 0
              ? fmt::format("  p-values: conformal ranks among {} clean calibration runs\n", result.calibrationRuns)
              : std::string("  p-values: the model's own calibration (--calibration RUNS ranks among clean runs: "
                            "sharper)\n");
  std::map<std::string, std::size_t> groups;
  for (const auto i : ranked) ++groups[result.scenes[i].group];
  for (const auto& [group, count] : groups) text += fmt::format("  {:>6}  {}\n", count, group);
  text += fmt::format("  scored {:.0f} scenes/s ({:.2f} s predicting and scoring), total {:.1f} s\n",
                      scoringSeconds > 0 ? static_cast<double>(n) / scoringSeconds : 0.0, scoringSeconds, seconds);
  text += fmt::format("report: {}\ntable:  {}\n", (output / "report.html").string(), (output / "deviations.csv").string());
  return text;
}

}  // namespace vsd::compare
