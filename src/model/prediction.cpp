// Predictor: a trained model (any decoder) or a predictor without training (cv, ca).
#include <fmt/format.h>

#include <cmath>
#include <cstring>

#include "checkpoint.hpp"
#include "kinematics.hpp"
#include "network.hpp"
#include "tensors.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/random.hpp"
#include "vsd/model/predictor.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {
// Scenes per forward pass: large enough to keep the matrix products efficient, small
// enough that activations (~6 MB) stay below glibc's mmap threshold and are recycled
// instead of being mapped and zeroed by the kernel for every operation.
constexpr std::size_t kPredictBatch = 512;
constexpr int kMaxSamples = 100000;
}  // namespace

double gaussianRegionRadius2(double level) { return -2.0 * std::log(1.0 - level); }

const std::vector<std::array<double, kCoverageLevels.size()>>* PositionRegions::find(const std::string& label) const {
  for (const auto& key : {label, std::string()}) {
    const auto found = byLabel.find(key);
    if (found != byLabel.end()) return &found->second;
  }
  return nullptr;
}

void PredictOptions::validate() const {
  if (samples < 0 || samples > kMaxSamples) {
    throw ConfigError::field("command line", "--samples", std::to_string(samples),
                             fmt::format("0 .. {} futures per scene", kMaxSamples));
  }
}

class Predictor::Backend {
 public:
  virtual ~Backend() = default;
  virtual const ModelInfo& info() const = 0;
  virtual bool probabilistic() const = 0;
  virtual bool predictsMotion() const = 0;
  virtual void checkCompatible(const vector::DatasetHeader& header, const std::string& what) const = 0;
  /// Predictions of scenes[first, last).
  virtual std::vector<Prediction> predict(const std::vector<vector::VectorizedScene>& scenes, std::size_t first,
                                          std::size_t last, const PredictOptions& options) const = 0;
};

namespace {

/// A stable 64-bit identity of a scene (label, sample index, Ego, t0): its draws do not
/// depend on which other scenes share its batch.
std::uint64_t sceneIdentity(const vector::VectorizedScene& scene) {
  std::uint64_t hash = 0xCBF29CE484222325ULL;  // FNV-1a
  const auto feed = [&hash](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001B3ULL;
  };
  feed(scene.label.data(), scene.label.size());
  feed(&scene.sample, sizeof(scene.sample));
  feed(scene.provenance.egoId.data(), scene.provenance.egoId.size());
  feed(&scene.provenance.t0, sizeof(scene.provenance.t0));
  return mix64(hash);
}

/// Standard-normal draws [B, S, width] for scenes[first, last), each scene from its own stream.
torch::Tensor samplingNoise(const std::vector<vector::VectorizedScene>& scenes, std::size_t first, std::size_t last,
                            const PredictOptions& options, std::int64_t width) {
  const auto n = static_cast<std::int64_t>(last - first);
  auto noise = torch::empty({n, options.samples, width});
  auto* data = noise.data_ptr<float>();
  const auto per_scene = static_cast<std::size_t>(options.samples) * static_cast<std::size_t>(width);
  for (std::int64_t i = 0; i < n; ++i) {
    Rng rng = Rng::derive(options.seed, sceneIdentity(scenes[first + static_cast<std::size_t>(i)]),
                          RandomStream::PredictionSamples);
    float* out = data + static_cast<std::size_t>(i) * per_scene;
    for (std::size_t j = 0; j < per_scene; ++j) out[j] = static_cast<float>(rng.normal(0.0, 1.0));
  }
  return noise;
}

/// One future from model-frame tensors [F, 2] (+ [F] kinematics when defined) into the scene frame.
class TrajectoryConverter {
 public:
  TrajectoryConverter(const SceneFrame& frame, const VehicleState& initial, double step)
      : frame_(frame), initial_(initial), step_(step) {}

  Trajectory operator()(const float* positions, const float* headings, const float* speeds, std::int64_t steps) const {
    Trajectory trajectory;
    trajectory.positions.reserve(static_cast<std::size_t>(steps));
    for (std::int64_t k = 0; k < steps; ++k) {
      trajectory.positions.push_back(frame_.toScene({positions[2 * k], positions[2 * k + 1]}));
    }
    if (headings == nullptr) return trajectory;
    trajectory.states.reserve(static_cast<std::size_t>(steps));
    double previous_speed = initial_.speed;
    for (std::int64_t k = 0; k < steps; ++k) {
      const Vec2 model_point(positions[2 * k], positions[2 * k + 1]);
      const double model_heading = headings[k];
      // A speed along the model-frame heading becomes |J u| times it in the scene (1 in the ego frame).
      const Vec2 direction = frame_.jacobian(model_point) * headingVector(model_heading);
      VehicleState state;
      state.x = trajectory.positions[static_cast<std::size_t>(k)].x();
      state.y = trajectory.positions[static_cast<std::size_t>(k)].y();
      state.heading = frame_.headingToScene(model_point, model_heading);
      state.speed = static_cast<double>(speeds[k]) * direction.norm();
      state.accel = (state.speed - previous_speed) / step_;
      previous_speed = state.speed;
      trajectory.states.push_back(state);
    }
    return trajectory;
  }

 private:
  const SceneFrame& frame_;
  VehicleState initial_;
  double step_;
};

/// Pointer to row `index` of a contiguous float tensor (or nullptr if undefined).
const float* rowOf(const torch::Tensor& tensor, std::int64_t index) {
  if (!tensor.defined()) return nullptr;
  return tensor.data_ptr<float>() + index * (tensor.numel() / tensor.size(0));
}

torch::Tensor contiguousOrUndefined(const torch::Tensor& tensor) {
  return tensor.defined() ? tensor.contiguous() : tensor;
}

/// The region radii of each step of a scene with `label`: the model's calibrated ones or
/// the Gaussian's.
std::vector<std::array<double, kCoverageLevels.size()>> regionRadii(const PositionRegions& regions,
                                                                    const std::string& label, std::int64_t steps) {
  if (const auto* calibrated = regions.find(label)) return *calibrated;
  std::array<double, kCoverageLevels.size()> gaussian{};
  for (std::size_t l = 0; l < kCoverageLevels.size(); ++l) gaussian[l] = gaussianRegionRadius2(kCoverageLevels[l]);
  return std::vector<std::array<double, kCoverageLevels.size()>>(static_cast<std::size_t>(steps), gaussian);
}

/// Decoded tensors of a batch -> Predictions in each scene's frame.
std::vector<Prediction> toPredictions(const std::vector<vector::VectorizedScene>& scenes, std::size_t first,
                                      const SceneTensors& tensors, const Decoded& decoded, const Sampled& sampled,
                                      double step, const PositionRegions& regions = {}) {
  const auto positions = decoded.positions.contiguous();
  const auto headings = contiguousOrUndefined(decoded.headings);
  const auto speeds = contiguousOrUndefined(decoded.speeds);
  const auto covariance = contiguousOrUndefined(decoded.covariance);
  const auto sample_positions = contiguousOrUndefined(sampled.positions);
  const auto sample_headings = contiguousOrUndefined(sampled.headings);
  const auto sample_speeds = contiguousOrUndefined(sampled.speeds);
  const std::int64_t steps = positions.size(1);
  const std::int64_t draws = sample_positions.defined() ? sample_positions.size(1) : 0;
  std::vector<Prediction> result(static_cast<std::size_t>(positions.size(0)));
  for (std::int64_t i = 0; i < positions.size(0); ++i) {
    const auto& frame = *tensors.frames[static_cast<std::size_t>(i)];
    const TrajectoryConverter convert(frame, scenes[first + static_cast<std::size_t>(i)].egoInitialState(), step);
    auto& prediction = result[static_cast<std::size_t>(i)];
    prediction.mostLikely = convert(rowOf(positions, i), rowOf(headings, i), rowOf(speeds, i), steps);
    if (covariance.defined()) {
      const float* c = rowOf(covariance, i);
      for (std::int64_t k = 0; k < steps; ++k) {
        Eigen::Matrix2d model_covariance;
        model_covariance << c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3];
        const float* p = rowOf(positions, i) + 2 * k;
        const Eigen::Matrix2d j = frame.jacobian({p[0], p[1]});
        prediction.positionCovariance.push_back(j * model_covariance * j.transpose());
      }
      prediction.regionRadius2 = regionRadii(regions, scenes[first + static_cast<std::size_t>(i)].label, steps);
    }
    for (std::int64_t s = 0; s < draws; ++s) {
      const std::int64_t row = i * draws + s;  // [B, S, ...] rows in order
      const auto at = [&](const torch::Tensor& t) -> const float* {
        return t.defined() ? t.data_ptr<float>() + row * (t.numel() / (t.size(0) * t.size(1))) : nullptr;
      };
      prediction.samples.push_back(convert(at(sample_positions), at(sample_headings), at(sample_speeds), steps));
    }
  }
  return result;
}

/// A trained VectorNet read from a model file.
class NetworkBackend final : public Predictor::Backend {
 public:
  NetworkBackend(const fs::path& path, const Decoders& decoders) : path_(path) {
    model_ = loadModel(path, info_, decoders);
  }

  const ModelInfo& info() const override { return info_; }
  bool probabilistic() const override { return model_.decoder->noiseWidth() > 0; }
  bool predictsMotion() const override {
    return info_.config.decoderRegistry().find(info_.config.decoder, path_.string()).kinematic;
  }

  void checkCompatible(const vector::DatasetHeader& header, const std::string& what) const override {
    const auto& config = info_.config;
    if (header.horizon != config.horizon || std::abs(header.step - config.step) > 1e-9) {
      throw ModelError(fmt::format("{}: {} steps of {} s, but the model {} predicts {} steps of {} s", what,
                                   header.horizon, header.step, path_.string(), config.horizon, config.step));
    }
  }

  std::vector<Prediction> predict(const std::vector<vector::VectorizedScene>& scenes, std::size_t first,
                                  std::size_t last, const PredictOptions& options) const override {
    c10::InferenceMode inference;
    model_.network->eval();
    const auto tensors = buildTensors(scenes, info_.config, first, last);
    const auto decoded = model_.decode(tensors);
    Sampled sampled;
    if (options.samples > 0 && probabilistic()) {
      const auto noise = samplingNoise(scenes, first, last, options, model_.decoder->noiseWidth());
      sampled = model_.decoder->sample(decoded, tensors.start, noise);
    }
    return toPredictions(scenes, first, tensors, decoded, sampled, info_.config.step, info_.positionRegions);
  }

 private:
  fs::path path_;
  ModelInfo info_;
  mutable Model model_;  // inference only: forward() is not const in libtorch
};

/// The predictors without training: one entry each, saying what acceleration the Ego keeps
/// along its initial heading. Both roll out through the same kinematic model as the
/// kinematic decoder (no reversing) (docs/models.md "Predictors without training").
struct MotionModel {
  const char* name;
  /// m/s^2: the acceleration held over the whole horizon of a scene.
  double (*acceleration)(const vector::VectorizedScene& scene);
};

/// ca: the acceleration over the last history step, from the speed over that step
/// (|p_0 - p_-1| / dt, the speed at its middle) and the speed at t0 (initial vector):
/// a = 2 (v_0 - u_-1/2) / dt, exact for constant acceleration within the step. 0 without
/// a valid history step ending at t0 (then ca predicts what cv does).
double lastObservedAcceleration(const vector::VectorizedScene& scene) {
  const auto& ego = scene.polylines.at(scene.egoPolyline);
  if (ego.vectors.size() < 2) return 0.0;
  const std::size_t last = ego.vectors.size() - 2;
  const auto& f = ego.vectors[last];
  if (!ego.valid[last] || std::abs(f[6]) > 1e-6) return 0.0;
  const double through_last_step = std::hypot(f[2] - f[0], f[3] - f[1]) / scene.step;
  return 2.0 * (scene.egoInitialState().speed - through_last_step) / scene.step;
}

double noAcceleration(const vector::VectorizedScene&) { return 0.0; }

constexpr MotionModel kMotionModels[] = {
    {"cv", noAcceleration},            // constant velocity
    {"ca", lastObservedAcceleration},  // constant acceleration: the last observed one
};

const MotionModel* findMotionModel(const fs::path& name) {
  for (const auto& model : kMotionModels) {
    if (name == model.name) return &model;
  }
  return nullptr;
}

class MotionModelBackend final : public Predictor::Backend {
 public:
  explicit MotionModelBackend(const MotionModel& motion) : motion_(motion) {
    info_.config.decoder = motion.name;
    info_.config.horizon = 0;
    info_.config.step = 0.0;
    info_.mix = "none (no training)";
    info_.trained = false;
  }

  const ModelInfo& info() const override { return info_; }
  bool probabilistic() const override { return false; }
  bool predictsMotion() const override { return true; }
  void checkCompatible(const vector::DatasetHeader&, const std::string&) const override {}

  std::vector<Prediction> predict(const std::vector<vector::VectorizedScene>& scenes, std::size_t first,
                                  std::size_t last, const PredictOptions&) const override {
    std::vector<Prediction> result;
    result.reserve(last - first);
    // One rollout per run of scenes sharing step and horizon (a dataset's scenes all do).
    for (std::size_t begin = first; begin < last;) {
      std::size_t end = begin + 1;
      while (end < last && scenes[end].step == scenes[begin].step &&
             scenes[end].target.size() == scenes[begin].target.size()) {
        ++end;
      }
      auto part = predictRun(scenes, begin, end);
      for (auto& prediction : part) result.push_back(std::move(prediction));
      begin = end;
    }
    return result;
  }

 private:
  std::vector<Prediction> predictRun(const std::vector<vector::VectorizedScene>& scenes, std::size_t first,
                                     std::size_t last) const {
    const auto n = static_cast<std::int64_t>(last - first);
    const auto steps = static_cast<std::int64_t>(scenes[first].target.size());
    const double step = scenes[first].step;
    auto speed = torch::empty({n});
    auto accel = torch::empty({n, 1});
    SceneTensors frames;
    for (std::int64_t i = 0; i < n; ++i) {
      const auto& scene = scenes[first + static_cast<std::size_t>(i)];
      speed[i] = scene.egoInitialState().speed;
      accel[i][0] = motion_.acceleration(scene);
      frames.frames.push_back(makeFrame("ego", scene, info_.config.laneSmoothing));
    }
    const auto path = rollout(torch::zeros({n, 2}), torch::zeros({n}), speed, accel.expand({n, steps}),
                              torch::zeros({n, steps}), step);
    Decoded decoded;
    decoded.positions = path.positions;
    decoded.headings = path.headings;
    decoded.speeds = path.speeds;
    return toPredictions(scenes, first, frames, decoded, Sampled{}, step);
  }

 private:
  const MotionModel& motion_;
  ModelInfo info_;
};

}  // namespace

bool Predictor::isBuiltin(const fs::path& model) { return findMotionModel(model) != nullptr; }

Predictor::Predictor(const fs::path& model, int threads, std::shared_ptr<const DecoderRegistry> decoders) {
  if (threads < 1 || threads > 256) {
    throw ConfigError::field("command line", "--threads", std::to_string(threads), "1 .. 256");
  }
  configureThreads(threads);
  if (const auto* motion = findMotionModel(model)) backend_ = std::make_unique<MotionModelBackend>(*motion);
  else backend_ = std::make_unique<NetworkBackend>(model, decoders);
}

Predictor::~Predictor() = default;

const ModelInfo& Predictor::info() const { return backend_->info(); }
const std::string& Predictor::name() const { return backend_->info().config.decoder; }
bool Predictor::probabilistic() const { return backend_->probabilistic(); }
bool Predictor::predictsMotion() const { return backend_->predictsMotion(); }

void Predictor::checkCompatible(const vector::DatasetHeader& header, const std::string& what) const {
  backend_->checkCompatible(header, what);
}

std::vector<Polyline> Predictor::predict(const std::vector<vector::VectorizedScene>& scenes) const {
  std::vector<Polyline> positions;
  positions.reserve(scenes.size());
  for (auto& prediction : predictDistribution(scenes, PredictOptions{})) {
    positions.push_back(std::move(prediction.mostLikely.positions));
  }
  return positions;
}

std::vector<Prediction> Predictor::predictDistribution(const std::vector<vector::VectorizedScene>& scenes,
                                                       const PredictOptions& options) const {
  options.validate();
  std::vector<Prediction> result;
  result.reserve(scenes.size());
  for (std::size_t first = 0; first < scenes.size(); first += kPredictBatch) {
    const std::size_t last = std::min(scenes.size(), first + kPredictBatch);
    auto part = backend_->predict(scenes, first, last, options);
    for (auto& prediction : part) result.push_back(std::move(prediction));
  }
  return result;
}

}  // namespace vsd::model
