// `vsd-sumo bench run | isolation | export | model | compare`: flags and printing; the
// measurements are the bench library's (vsd/bench/). The other benchmarks add themselves
// from their own files (bench_*.cpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/bench/model_bench.hpp"
#include "vsd/bench/process_bench.hpp"
#include "vsd/bench/run_bench.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

bench::Tool benchTool() { return {siblingExecutable("vsd-sumo")}; }

namespace {

void printMpi(const std::optional<bench::MpiComparison>& mpi) {
  if (!mpi) {
    fmt::print("  MPI: not in this build (no rank comparison)\n");
    return;
  }
  fmt::print("  mpirun -n 1 vs -n 2 (--samples {}): {:.1f} vs {:.1f} scenarios/s = {:.2f}x; merging the 2 shards "
             "{:.2f} s; merged outputs byte-identical to one process: {}\n",
             mpi->samples, mpi->one.rate(), mpi->two.rate(), mpi->two.rate() / mpi->one.rate(), mpi->mergeSeconds,
             mpi->identical ? "yes" : "NO");
}

int printRunBench(const bench::RunBenchOptions& options) {
  fmt::print("vsd-sumo bench run: {} (jobs {}), end to end: sample -> net -> simulate -> metrics -> files; load "
             "average before: {}\n",
             options.scenario.string(), options.jobs, bench::loadAverage());
  const auto result = bench::runBench(options);
  fmt::print("  {:<36} {:>8} {:>10} {:>14} {:>16}\n", "mode", "samples", "seconds", "scenarios/s", "CPU ms/scenario");
  auto print_row = [](const std::string& mode, const bench::RunMeasurement& measurement) {
    fmt::print("  {:<36} {:>8} {:>10.2f} {:>14.1f} {:>16.3f}\n", mode, measurement.samples, measurement.seconds,
               measurement.rate(), measurement.cpuMillisecondsPerSample());
  };
  print_row(fmt::format("batch {}", result.batched.batch), result.batched);
  // Per road user and step, the unit of the issue-23 target (every process of the run counted).
  fmt::print("  {:<36} {:>8} {:>10} {:>14} {:>16.2f}  ({} road users x {} steps)\n", "  CPU us per simulated vehicle-step",
             "", "", "", result.cpuMicrosecondsPerVehicleStep(), result.roadUsers, result.steps);
  print_row(fmt::format("batch {}, --net-writer netconvert", result.netconvert.batch), result.netconvert);
  print_row("batch 1 (net + sim each)", result.single);
  fmt::print("  speed-up of batching: {:.0f}x; CPU time per scenario counts every process of the run\n",
             result.batched.rate() / result.single.rate());
  fmt::print("  peak memory (RSS) as --samples grows:\n");
  for (const auto& memory : result.memory) {
    fmt::print("    --samples {:>7}: {:>7.1f} MiB ({:.0f} scenarios/s)\n", memory.samples,
               static_cast<double>(memory.maxRssKiB) / 1024.0, memory.rate());
  }
  printMpi(result.mpi);
  return 0;
}

void printIsolationRuns(const bench::IsolationBenchResult& result, double n) {
  for (const auto& m : result.runs) {
    const auto& p = m.parent;
    const auto& w = m.workers;
    fmt::print("  {:<5} {:<9} {:>8.2f} {:>11.1f} {:>8.3f} {:>5.3f}+{:.3f} {:>5.3f}+{:.3f} {:>14.0f} {:>14.0f}\n", m.round,
               bench::isolationName(m.isolation), m.seconds, n / m.seconds, 1000.0 * m.cpu() / n, 1000.0 * p.user / n,
               1000.0 * p.system / n, 1000.0 * w.user / n, 1000.0 * w.system / n, p.pageFaults / n, w.pageFaults / n);
  }
}

int printIsolationBench(const bench::IsolationBenchOptions& options) {
  using Isolation = pipeline::RunOptions::Isolation;
  fmt::print("vsd-sumo bench isolation: {}, --samples {} --net-batch {} --jobs 1, {} rounds (order alternating); load "
             "average before: {}\n",
             options.scenario.string(), options.samples, options.batch, options.rounds, bench::loadAverage());
  fmt::print("  per scenario: CPU ms = user + system of the parent and its workers; faults = minor page faults\n");
  fmt::print("  {:<5} {:<9} {:>8} {:>11} {:>8} {:>12} {:>12} {:>14} {:>14}\n", "round", "isolation", "seconds",
             "scenarios/s", "CPU ms", "parent u+s", "workers u+s", "parent faults", "workers faults");
  const auto result = bench::runIsolationBench(options);
  const auto n = static_cast<double>(options.samples);
  printIsolationRuns(result, n);
  const auto none = result.medians(Isolation::None), process = result.medians(Isolation::Process);
  fmt::print("  medians: CPU {:.3f} (none) vs {:.3f} (process) ms/scenario = {:+.1f} % (system time {:.3f} vs {:.3f}); "
             "wall {:.2f} vs {:.2f} s = {:+.1f} %\n",
             1000.0 * none.cpu / n, 1000.0 * process.cpu / n, 100.0 * (process.cpu / none.cpu - 1.0),
             1000.0 * none.system / n, 1000.0 * process.system / n, none.wall, process.wall,
             100.0 * (process.wall / none.wall - 1.0));
  fmt::print("  outputs (concrete.csv, traces.h5, dataset.h5) byte-identical: {}\n", result.identical ? "yes" : "NO");
  fmt::print("  of the difference: encoding + decoding the outcomes for the pipe {:.3f} ms CPU per scenario ({:.1f} "
             "KiB per scenario)\n",
             result.codecMilliseconds, result.codecBytes / 1024.0);
  fmt::print("  starting a worker (fork + exit, no work) {:.2f} ms CPU; a run starts two (controller probe, worker): "
             "{:.4f} ms per scenario\n",
             result.forkMilliseconds, 2.0 * result.forkMilliseconds / n);
  fmt::print("  load average after: {}\n", bench::loadAverage());
  return 0;
}

int printMapExportBench(const bench::MapExportBenchOptions& options) {
  fmt::print("vsd-sumo bench export: {} (--egos {}), one process, defaults otherwise\n", options.map.string(),
             options.egos);
  fmt::print("  {:<22} {:>9} {:>9} {:>12} {:>14} {:>10}\n", "mode", "sim [s]", "samples", "samples/s", "bytes/sample",
             "peak RSS");
  const auto result = bench::runMapExportBench(options);
  auto print_row = [](const bench::MapExportMeasurement& m) {
    fmt::print("  {:<22} {:>9.0f} {:>9.0f} {:>12.0f} {:>14.0f} {:>7.1f} MiB\n",
               fmt::format("compression {}", m.compression), m.end, m.samples, m.samples / m.seconds,
               m.bytesPerSample, static_cast<double>(m.maxRssKiB) / 1024.0);
  };
  for (const auto& m : result.modes) print_row(m);
  fmt::print("  peak memory as the number of samples grows (compression 1):\n");
  for (const auto& m : result.memory) print_row(m);
  return 0;
}

/// For the metrics of the issue (a_min, d_min, lane_offset_max where the scenario has
/// them): the MAE and bias of the most likely future's metric against the simulated value,
/// the floor (the metric of the simulated positions), and for sampled futures the MAE of
/// their median and the coverage of their 50 % / 90 % intervals.
void printMetricAccuracy(const bench::MetricAccuracy& accuracy) {
  fmt::print("    {:<16} {:>7} {:>9} {:>9} {:>11} {:>11} {:>9} {:>9}\n", accuracy.label, "scenes", "MAE", "bias",
             "MAE floor", "MAE median", "cover 50%", "cover 90%");
  for (const auto& m : accuracy.statistics.metrics) {
    if (m.name != "a_min" && m.name != "d_min" && m.name != "lane_offset_max") continue;
    auto drawn = [&](double value) { return m.intervalPairs ? fmt::format("{:.3f}", value) : std::string("-"); };
    fmt::print("    {:<16} {:>7} {:>9.3f} {:>+9.3f} {:>11} {:>11} {:>9} {:>9}\n", m.name, m.pairs, m.mae, m.bias,
               m.floorMae ? fmt::format("{:.3f}", *m.floorMae) : std::string("-"), drawn(m.medianDrawMae),
               drawn(m.coverage50), drawn(m.coverage90));
  }
}

void printMix(const bench::MixResult& result) {
  fmt::print("  mix {:<32} trained in {:>5.1f} s ({} epochs, {:.0f} samples/s), validation ADE [m]:", result.mix,
             result.summary.seconds, result.summary.plannedEpochs, result.summary.samplesPerSecond);
  for (const auto& [label, errors] : result.evaluation.perLabel) fmt::print(" {} {:.3f}", label, errors.ade);
  fmt::print("\n");
  if (result.evaluation.overall.scored > 0) fmt::print("{}", result.evaluation.table());
}

void printThroughput(const bench::ModelBench& bench, const bench::MixResult& all, double simulation_rate) {
  const auto& options = bench.options();
  const double inference_rate = static_cast<double>(all.evaluation.overall.samples) / all.evaluation.predictionSeconds;
  fmt::print("  training throughput: {:.0f} samples/s; {} samples to convergence (end of the schedule) in {:.1f} s\n",
             all.summary.samplesPerSecond, 3 * options.samples, all.summary.seconds);
  fmt::print("  inference: {:.0f} scenes/s batched (most likely future)", inference_rate);
  if (simulation_rate > 0.0) {
    fmt::print(" = {:.1f}x the simulation throughput of `vsd-sumo run` ({:.0f} scenarios/s, acc_lk)",
               inference_rate / simulation_rate, simulation_rate);
  }
  fmt::print("\n");
  if (const auto rate = bench.samplingRate()) {
    fmt::print("  inference with {} sampled futures per scene: {:.0f} scenes/s\n", options.draws, *rate);
  }
}

int printModelBench(const bench::ModelBenchOptions& model_options) {
  bench::ModelBench bench(model_options);
  const auto& options = bench.options();
  fmt::print("vsd-sumo bench model: VectorNet on {} training (seed {}) + {} validation samples (seed {}) per functional "
             "scenario ({} threads)\n",
             options.samples, kTrainingDataSeed, options.validationSamples, kValidationDataSeed, options.threads);
  const double simulation_rate = bench.generateData();
  const auto& config = bench.modelConfig();
  std::vector<std::string> decoder_options;
  for (const auto& [name, value] : config.decoderOptions) decoder_options.push_back(fmt::format("{}={}", name, value));
  fmt::print("  preset {}: decoder {}{}{}, frame {} (lane smoothing {} m), {} optimizer steps\n", options.preset,
             config.decoder, decoder_options.empty() ? "" : " ", fmt::join(decoder_options, " "), config.frame,
             config.laneSmoothing, options.steps);
  const auto all = bench.trainAll();
  printMix(all);
  fmt::print("  metrics of the all-three model's predictions vs. fresh SUMO runs of the validation scenarios (as `vsd-sumo "
             "compare`); floor: metric of the simulated positions; intervals of {} sampled futures:\n",
             options.draws);
  for (const auto& accuracy : bench.metricAccuracy()) printMetricAccuracy(accuracy);
  if (options.singles) {
    for (const auto& label : bench::modelBenchLabels()) printMix(bench.trainSingle(label));
  }
  if (options.row4) {
    fmt::print("  row 4 (ACC + LK -> ACC&LK): the acc_lk column below\n");
    printMix(bench.trainRow4());
  }
  printThroughput(bench, all, simulation_rate);
  return 0;
}

int printCompareBench(const bench::CompareBenchOptions& options) {
  fmt::print("vsd-sumo bench compare: {} with {} (jobs {}), end to end: vectorize -> predict -> simulate -> "
             "compare -> report\n",
             options.scenario.string(), options.model.string(), options.jobs);
  fmt::print("  {:>8} {:>10} {:>14} {:>14} {:>12}\n", "samples", "seconds", "scenarios/s", "report [MiB]", "peak RSS");
  for (const auto& m : bench::runCompareBench(options)) {
    fmt::print("  {:>8} {:>10.2f} {:>14.1f} {:>14.2f} {:>8.1f} MiB\n", m.samples, m.seconds,
               static_cast<double>(m.samples) / m.seconds, m.reportMiB, static_cast<double>(m.maxRssKiB) / 1024.0);
  }
  return 0;
}

void addRunBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::RunBenchOptions>();
  CLI::App* run = bench.add_subcommand("run", "Throughput and peak memory of `vsd-sumo run`");
  run->add_option("scenario", options->scenario, "Logical scenario")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(run, "--samples", options->samples, "Samples for the batched run")->capture_default_str();
  addNumber(run, "--batch-one-samples", options->batchOneSamples, "Samples for the --net-batch 1 run")
      ->capture_default_str();
  addNumber(run, "--memory-samples", options->memorySamples, "Sample counts for the memory runs")
      ->capture_default_str();
  addNumber(run, "--net-batch", options->batch, "Samples per SUMO network of the batched runs")->capture_default_str();
  addNumber(run, "--jobs", options->jobs, "Worker processes")->capture_default_str();
  addNumber(run, "--mpi-samples", options->mpiSamples, "Samples for the MPI runs (1 rank vs 2)")
      ->capture_default_str();
  run->callback([options, &context] {
    options->tool = benchTool();
    context.action = [options] { return printRunBench(*options); };
  });
}

void addIsolationBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::IsolationBenchOptions>();
  CLI::App* isolation = bench.add_subcommand(
      "isolation", "CPU and wall time of `run` --jobs 1 with its controllers and libsumo in a worker process vs in "
                   "this process");
  isolation->add_option("scenario", options->scenario, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  addNumber(isolation, "--samples", options->samples, "Samples per run")->capture_default_str();
  addNumber(isolation, "--net-batch", options->batch, "Samples per SUMO network")->capture_default_str();
  addNumber(isolation, "--rounds", options->rounds, "Rounds of both runs")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  isolation->callback([options, &context] { context.action = [options] { return printIsolationBench(*options); }; });
}

void addMapExportBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::MapExportBenchOptions>();
  CLI::App* exporting = bench.add_subcommand("export", "Throughput, size and peak memory of `vsd-sumo export`");
  exporting->add_option("map", options->map, "SUMO configuration")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(exporting, "--end", options->end, "Simulated seconds")->capture_default_str();
  exporting->add_option("--egos", options->egos, "Ego selection")->capture_default_str();
  addNumber(exporting, "--memory-ends", options->memoryEnds, "Simulated seconds for the memory runs")
      ->capture_default_str();
  exporting->callback([options, &context] {
    options->tool = benchTool();
    context.action = [options] { return printMapExportBench(*options); };
  });
}

void addModelBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::ModelBenchOptions>();
  CLI::App* modeling = bench.add_subcommand("model", "Training and inference throughput and validation ADE of VectorNet (the data configurations are chosen on)");
  modeling->add_option("--work", options->work, "Keep data and models in this folder (reused when present)");
  addNumber(modeling, "--samples", options->samples, "Training samples per functional scenario")->capture_default_str();
  addNumber(modeling, "--validation-samples,--test-samples", options->validationSamples,
            "Validation samples per functional scenario (fresh scenarios of the validation seed; --test-samples: its old name)")
      ->capture_default_str();
  modeling->add_flag("--singles", options->singles, "Also train one model per functional scenario");
  addNumber(modeling, "--threads", options->threads, "libtorch threads")->capture_default_str();
  modeling->add_option("--preset", options->preset,
                       "The configuration trained, as `train --preset` (docs/models.md \"Presets\")")
      ->capture_default_str();
  modeling->add_option("--decoder", options->decoder, "Another decoder than the preset's (its own default options)");
  modeling->add_option("--decoder-option", options->decoderOptions,
                       "Decoder option name=value on top of the preset's (repeatable)");
  modeling->add_option("--steps", options->steps, "Optimizer steps of every training")->capture_default_str();
  modeling->add_flag("--resume", options->resume,
                     "Continue trainings from <model>.last where it exists; reuse finished models");
  modeling->add_flag("--row4", options->row4, "Also train on acc + lk only and measure on acc_lk (paper row 4)");
  modeling->add_option("--frame", options->frame, "Another model frame than the preset's (ego, lane)");
  modeling->add_option_function<double>(
      "--lane-smoothing", [options](double metres) { options->laneSmoothing = metres; },
      "m: half-width of the lane frame's smoothing of its reference line (default: train's)");
  addNumber(modeling, "--futures", options->draws, "Sampled futures per scene in the inference benchmark")
      ->capture_default_str();
  modeling->callback([options, &context] {
    options->tool = benchTool();
    context.action = [options] { return printModelBench(*options); };
  });
}

void addCompareBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::CompareBenchOptions>();
  CLI::App* comparing = bench.add_subcommand("compare", "Wall time, report size and peak memory of `vsd-sumo compare`");
  comparing->add_option("--model", options->model, "VectorNet model file")->required()->check(CLI::ExistingFile);
  comparing->add_option("scenario", options->scenario, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  addNumber(comparing, "--samples", options->samples, "Scenario counts to compare")->capture_default_str();
  addNumber(comparing, "--jobs", options->jobs, "SUMO worker processes")->capture_default_str();
  comparing->callback([options, &context] {
    options->tool = benchTool();
    context.action = [options] { return printCompareBench(*options); };
  });
}

}  // namespace

void addBenchCommand(CLI::App& app, CommandContext& context) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks whose output is recorded under results/ (docs/benchmarks.md)");
  bench->require_subcommand(1);
  addRunBench(*bench, context);
  addIsolationBench(*bench, context);
  addMapExportBench(*bench, context);
  addModelBench(*bench, context);
  addCompareBench(*bench, context);
  addInteropBench(*bench, context);
  addImportBench(*bench, context);
  addLibraryBench(*bench, context);
  addSearchBench(*bench, context);
  addDeviationsBench(*bench, context);
  addTrainBench(*bench, context);
  addReferenceBench(*bench, context);
}

}  // namespace vsd::cli
