#pragma once
// The experiment YAML as typed structs (internal to the experiment module).

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "vsd/baseline/baseline.hpp"

namespace vsd::experiment {

struct Source {
  std::string label;
  std::filesystem::path scenario;  ///< a logical scenario to simulate, or
  std::filesystem::path trainRun;  ///< existing run folders
  std::filesystem::path testRun;
};

/// What a leave-one-out row trains on, for its held-out functional scenario (docs/results.md
/// "Leave one scenario out"): the paper's rows 9 and 10 asked of every scenario.
enum class HeldOutTraining {
  Others,           ///< every other functional scenario, `others` samples each
  OthersAndFewOwn,  ///< the same plus `few_shot` of its own (row 9)
  FewOwn,           ///< `few_shot` of its own alone (row 10)
  AllOwn,           ///< `alone` of its own alone (the reference row 9 is held to)
};
inline constexpr HeldOutTraining kHeldOutTrainings[] = {HeldOutTraining::Others, HeldOutTraining::OthersAndFewOwn,
                                                        HeldOutTraining::FewOwn, HeldOutTraining::AllOwn};
/// Its name in CSV files and the manifest ("others", "others_and_few_own", "few_own", "all_own").
const char* heldOutTrainingId(HeldOutTraining training);

struct AdeSpec {
  int row = 0;
  std::vector<std::pair<std::string, std::size_t>> mix;
  std::map<std::string, double> paper;
  /// A leave-one-out row: the held-out label (its test set is the only one it is evaluated
  /// on) and what it trains on; empty for the table rows of the spec's `ade`.
  std::string heldOut;
  HeldOutTraining training = HeldOutTraining::Others;
};

/// `leave_one_out`: each of `heldOut` in turn predicted from the others (the rows it expands
/// into are AdeSpec rows numbered from kFirstHeldOutRow, four per held-out scenario).
struct LeaveOneOutSpec {
  std::vector<std::string> heldOut;  ///< every label but `context` unless the spec names them
  std::vector<std::string> context;  ///< always trained on, never held out (the paper's three)
  std::size_t others = 1000;         ///< samples of each other functional scenario
  std::size_t fewShot = 200;         ///< own samples added (row 9) or alone (row 10)
  std::size_t alone = 2000;          ///< own samples of the reference row
  std::vector<std::string> metrics;  ///< reported for a held-out scenario whose data store them
};
inline constexpr int kFirstHeldOutRow = 1001;

/// A way of training every ADE row (README "experiment: models"). The first model of a
/// spec is the main one: its rows decide the findings and predict in the MAE table and figures.
struct ModelSpec {
  std::string name;                        ///< names the rows in the tables and the cache folders
  std::string decoder = "offsets";         ///< a name of model::builtinDecoders()
  std::map<std::string, double> options;   ///< decoder options (the rest take the decoder's defaults)
  std::string frame = "ego";               ///< the model's coordinate frame (model::availableFrames())
  std::vector<int> rows;                   ///< ade rows trained this way (every row unless the spec names them)
  /// Seeds every row of this model is trained with (seed .. seed + seeds - 1, mean ± std in
  /// the tables); 0: the spec's `seeds` section decides (the main model's rows it names).
  int seeds = 0;
  bool trains(int row) const;
};

struct MaeMetricSpec {
  std::string label;
  std::string metric;
  std::map<std::string, double> paper;  ///< et, bnn, vectornet
};

struct FigureSpec {
  std::string name;
  int row = 0;
  std::string title;
};

struct Spec {
  std::filesystem::path file;
  std::string name;
  std::uint64_t seed = 1;
  std::vector<Source> sources;
  std::uint64_t trainSamples = 3000;
  std::uint64_t testSamples = 10000;
  std::uint64_t trainSeed = 1;
  std::uint64_t testSeed = 2;
  int jobs = 2;
  int steps = 6000;
  int batch = 64;
  double learningRate = 2e-3;
  int threads = 2;                         ///< libtorch threads of one training (part of a model's key)
  int parallel = 1;                        ///< trainings at a time; threads * parallel cores in all
  /// Threads for the work that is not split into trainings (evaluations, the BNN).
  int cores() const { return threads * parallel; }
  std::vector<AdeSpec> ade;
  std::vector<ModelSpec> models;           ///< never empty after parsing (default: one offsets model)
  int seedCount = 1;                       ///< seeds seed .. seed + seedCount - 1 for `seedRows` of the main model
  std::vector<int> seedRows;
  std::vector<std::string> predictors;     ///< predictors without training ("cv", "ca") as extra rows
  std::size_t maeSamples = 2000;
  std::map<std::string, int> vectornetRows;
  int maeDraws = 32;                       ///< sampled futures per test scene of a probabilistic model (interval coverage)
  std::vector<MaeMetricSpec> maeMetrics;
  baseline::ExtraTreesOptions extraTrees;
  baseline::BnnOptions bnn;
  std::vector<FigureSpec> figures;
  LeaveOneOutSpec leaveOneOut;
  bool quick = false;

  const Source& source(const std::string& label) const;
  const AdeSpec& row(int number) const;
};

/// Parses and checks the spec; with `quick`, applies its `quick:` section.
Spec parseSpec(const std::filesystem::path& file, bool quick);

}  // namespace vsd::experiment
