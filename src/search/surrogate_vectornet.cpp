// `vectornet`: the model module's VectorNet with the probabilistic `kinematic` decoder in
// the lane frame, learning from vectorized scenes instead of inputs: the executions' scenes with their
// simulated futures train it (fine-tuned from a model of the --prior datasets); each
// candidate is vectorized before simulation (pipeline::plannedScene), S futures are sampled
// from its predictive distribution, every future's metrics come from the metric registry
// (the code `compare` scores predictions with), and the probability is the share of futures
// meeting the criterion (where none does, a Gaussian tail below 1 / (2 S) that ranks by
// closeness).
// Every round trains on all the search's scenes so far: from scratch, or with --prior
// fine-tuning a model pre-trained on the prior datasets once per search.
// A criterion column that is no metric of the Ego's own future (with --reference the
// reference driver's outcome, `reference_d_min`) cannot come from the scenes, which carry
// the system's future only: it is learnt from the inputs by extra trees, as the
// `extra-trees` surrogate learns it, and every sampled future is judged with every tree's
// prediction (the two are independent given the scenario).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "search_internal.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/search/surrogate.hpp"

namespace fs = std::filesystem;

namespace vsd::search {

namespace {

/// Candidates predicted per batch: bounds the memory of scenes and sampled futures.
constexpr std::size_t kChunk = 512;
/// The prior model's training: this many rounds' steps (2,000 by default, ~1 min on one thread).
constexpr int kPriorStepsPerRound = 5;

class VectorNetSurrogate final : public Surrogate {
 public:
  explicit VectorNetSurrogate(const SurrogateOptions& options) : options_(options) {}

  bool guidesSelection() const override { return true; }

  void fit(const TrainingSet& data) override {
    if (!options_.metricSet) throw Error("internal: vectornet surrogate without a metric set");
    model::TrainOptions train = trainingOptions(options_.seed);
    setOwnLabelData(data, train);
    if (!data.priorScenes.empty()) train.initialModel = priorModel(data.priorScenes);
    train.output = options_.modelFile;
    train.steps = options_.vectornetSteps;
    model::train(train);
    fs::remove(options_.modelFile.string() + ".last");  // resume state of the training: not needed
    predictor_ = std::make_unique<model::Predictor>(options_.modelFile, options_.threads);
    fitInputModels(data);
  }

  std::vector<double> probability(const CandidateSet& candidates, const Criterion& criterion) const override {
    const auto rows = static_cast<std::size_t>(candidates.x.rows());
    std::vector<double> result(rows, 0.0);
    std::vector<std::vector<Matrix>> per_tree;  // per input model: one [rows, 1] prediction per tree
    for (const auto& input_model : inputModels_) per_tree.push_back(input_model.forest.predictPerTree(candidates.x));
    model::PredictOptions predict;
    predict.samples = options_.futureSamples;
    predict.seed = options_.seed;
    for (std::size_t first = 0; first < rows; first += kChunk) {
      throwIfInterrupted();
      std::vector<vector::VectorizedScene> scenes;
      std::vector<std::size_t> which;
      for (std::size_t row = first; row < std::min(rows, first + kChunk); ++row) {
        try {
          scenes.push_back(candidates.scene(row));
          // A planned scene records no future (targets invalid), and metricsOfFuture judges a
          // future only where the target is valid: the whole horizon, as a completed run has it.
          std::fill(scenes.back().targetValid.begin(), scenes.back().targetValid.end(), 1);
          which.push_back(row);
        } catch (const ConfigError&) {
          // Cannot be planned (a vehicle off its road): the simulation fails it too; p = 0.
        }
      }
      if (scenes.empty()) continue;
      const auto predictions = predictor_->predictDistribution(scenes, predict);
      for (std::size_t k = 0; k < scenes.size(); ++k) {
        result[which[k]] = shareMeeting(scenes[k], predictions[k], inputDraws(per_tree, which[k]), criterion);
      }
    }
    return result;
  }

 private:
  /// The training every model of the surrogate shares: the kinematic decoder (probabilistic,
  /// its futures carry speeds and accelerations) in the lane frame, in which data of other
  /// functional scenarios (--prior) transfer: trained on acc + lk alone it predicts acc_lk at
  /// 0.38 m ADE, the Ego frame at 3.2 m (README "Row 4"). accel_weight 10 as in
  /// results/paper: d_min and ttc_min depend on the braking.
  model::TrainOptions trainingOptions(std::uint64_t seed) const {
    model::TrainOptions train;
    train.config.decoder = "kinematic";
    train.config.decoderOptions = {{"accel_weight", 10.0}};
    train.config.frame = "lane";
    train.seed = seed;
    train.threads = options_.threads;
    train.patience = 1'000'000;  // the whole (short) schedule; the best epoch by validation ADE is kept
    return train;
  }

  /// The model pre-trained on the priors alone, once per search (kPriorStepsPerRound rounds'
  /// steps). Every round fine-tunes it on the search's own scenes instead of mixing the priors
  /// in: measured (README "Transfer"), the mix made acc_lk searches with priors of acc + lk
  /// find fewer critical scenarios than their cold start, fine-tuning more. Written under a
  /// temporary name and renamed when complete, so that a search killed meanwhile retrains it.
  fs::path priorModel(const std::vector<fs::path>& priors) const {
    const auto& file = options_.priorModelFile;
    if (fs::exists(file)) return file;
    model::TrainOptions train = trainingOptions(options_.priorSeed);
    train.data = priors;
    train.output = file.string() + ".partial";
    train.steps = kPriorStepsPerRound * options_.vectornetSteps;
    model::train(train);
    fs::remove(train.output.string() + ".last");
    fs::rename(train.output, file);
    return file;
  }

  /// Every own scene, and every prior scene of the scenario's own label (e.g. an earlier
  /// search of it: as good as own data). Priors of other labels train the prior model only,
  /// so their files stay out of the rounds' trainings (which would hash and scan them).
  static void setOwnLabelData(const TrainingSet& data, model::TrainOptions& train) {
    vector::DatasetCollection own;
    for (const auto& path : data.scenes) own.add(path);
    auto counts = own.labelCounts();
    train.data = data.scenes;
    for (const auto& prior : data.priorScenes) {
      vector::DatasetCollection file;
      file.add(prior);
      bool shares_a_label = false;
      for (const auto& [label, available] : file.labelCounts()) {
        const auto it = counts.find(label);
        if (it == counts.end()) continue;
        it->second += available;
        shares_a_label = true;
      }
      if (shares_a_label) train.data.push_back(prior);
    }
    train.mix = {};
    for (const auto& [label, count] : counts) train.mix.counts.emplace_back(label, count);
  }

  /// Share of the (sampled future, input-model tree) pairs whose values meet the criterion
  /// (pairs it cannot judge — a metric that cannot be computed, an expression that gives
  /// NaN — do not count; without input models every future is one pair). Where none meets
  /// it (a rare criterion: most candidates), the share is 0 everywhere and cannot rank; then
  /// the Gaussian tail of the criterion's values (their mean and spread, tailProbability)
  /// ranks by closeness, scaled below 1 / (2 P), P the pairs judged, so that it stays below
  /// every candidate with a pair that meets it.
  double shareMeeting(const vector::VectorizedScene& scene, const model::Prediction& prediction,
                      const std::vector<std::vector<double>>& input_draws, const Criterion& criterion) const {
    const auto& used = criterion.usedColumns();
    const std::size_t own = options_.metricSet->names().size();
    std::vector<std::vector<double>> draws(used.size());
    for (std::size_t k = 0; k < inputModels_.size(); ++k) draws[inputModels_[k].slot] = input_draws[k];
    const std::size_t pairs_per_future = inputModels_.empty() ? 1 : input_draws.front().size();
    std::vector<double> values(used.size());
    std::size_t judged = 0;
    std::size_t meeting = 0;
    for (const auto& future : prediction.samples) {
      const auto metrics = pipeline::metricsOfFuture(*options_.metricSet, scene, future.positions, future.states);
      bool computable = true;
      for (std::size_t m = 0; m < used.size(); ++m) {
        if (used[m] >= own) continue;
        values[m] = metrics[used[m]];
        computable = computable && !std::isnan(values[m]);
      }
      if (!computable) continue;
      std::size_t judged_here = 0;
      for (std::size_t t = 0; t < pairs_per_future; ++t) {
        for (std::size_t k = 0; k < inputModels_.size(); ++k) values[inputModels_[k].slot] = input_draws[k][t];
        const auto verdict = criterion.verdictOfUsed(values);
        if (!verdict) continue;
        ++judged_here;
        meeting += *verdict ? 1 : 0;
      }
      if (judged_here == 0) continue;
      judged += judged_here;
      for (std::size_t m = 0; m < used.size(); ++m) {
        if (used[m] < own) draws[m].push_back(values[m]);
      }
    }
    if (judged == 0) return 0.0;
    if (meeting > 0) return static_cast<double>(meeting) / static_cast<double>(judged);
    // Below every candidate with a pair that meets it: the smallest such share is 1 / judged.
    return tailProbabilityOf(draws, criterion) / (2.0 * static_cast<double>(judged));
  }

  /// One forest per criterion column that is not a metric of the Ego's own future (the
  /// --reference driver's outcome), fitted on the inputs like the `extra-trees` surrogate.
  void fitInputModels(const TrainingSet& data) {
    const std::size_t own = options_.metricSet->names().size();
    inputModels_.clear();
    for (std::size_t slot = 0; slot < data.columns.size(); ++slot) {
      if (data.columns[slot] < own) continue;
      inputModels_.push_back({slot, detail::fitForest(data.x, data.y.col(static_cast<Eigen::Index>(slot)),
                                                      options_.trees, options_.seed + static_cast<std::uint64_t>(slot))});
    }
  }

  /// Candidate `row`'s predictions of every input model, one per tree.
  std::vector<std::vector<double>> inputDraws(const std::vector<std::vector<Matrix>>& per_tree, std::size_t row) const {
    std::vector<std::vector<double>> draws;
    for (const auto& trees : per_tree) {
      draws.emplace_back();
      for (const auto& prediction : trees) draws.back().push_back(prediction(static_cast<Eigen::Index>(row), 0));
    }
    return draws;
  }

  /// tailProbability of the draws' mean and standard deviation per metric (finite draws
  /// only; 0 when a metric has none, e.g. ttc_min of futures that never close in).
  static double tailProbabilityOf(const std::vector<std::vector<double>>& draws, const Criterion& criterion) {
    std::vector<double> centre(draws.size());
    std::vector<double> spread(draws.size());
    for (std::size_t m = 0; m < draws.size(); ++m) {
      double sum = 0.0;
      double squares = 0.0;
      std::size_t finite = 0;
      for (const double value : draws[m]) {
        if (!std::isfinite(value)) continue;
        sum += value;
        squares += value * value;
        ++finite;
      }
      if (finite == 0) return 0.0;
      centre[m] = sum / static_cast<double>(finite);
      spread[m] = std::sqrt(std::max(0.0, squares / static_cast<double>(finite) - centre[m] * centre[m]));
    }
    return tailProbability(centre, spread, criterion);
  }

  /// A criterion column learnt from the inputs: its position among Criterion::usedColumns.
  struct InputModel {
    std::size_t slot;
    baseline::ExtraTrees forest;
  };

  SurrogateOptions options_;
  std::unique_ptr<model::Predictor> predictor_;
  std::vector<InputModel> inputModels_;
};

}  // namespace

std::unique_ptr<Surrogate> makeVectorNetSurrogate(const SurrogateOptions& options) {
  return std::make_unique<VectorNetSurrogate>(options);
}

}  // namespace vsd::search
