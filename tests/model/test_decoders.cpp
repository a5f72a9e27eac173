// Decoders: the registry, the kinematic vehicle model in libtorch, the kinematic decoder's
// distribution, predictors without training, sampling, intervals and calibration scores.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <csignal>
#include <functional>
#include <cmath>
#include <algorithm>
#include <random>
#include <tuple>

#include "../../src/model/calibration.hpp"
#include "../../src/model/decoder.hpp"
#include "../../src/model/kinematics.hpp"
#include "../../src/model/network.hpp"
#include "../../src/model/tensors.hpp"
#include "extension/constant_accel_decoder.hpp"
#include "synthetic_scenes.hpp"
#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/random.hpp"
#include "vsd/model/presets.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/sim/vehicle_model.hpp"

using namespace vsd;
using namespace vsd::model;
using namespace vsd::test;
namespace fs = std::filesystem;

namespace {

std::string errorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

/// Trains a tiny model of `decoder` for `steps` steps on `samples` synthetic scenes into
/// `dir`/`file`; returns the options it was trained with.
TrainOptions trainTiny(const TemporaryDirectory& dir, const std::string& decoder, std::size_t samples, int steps,
                       const std::string& file) {
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", samples), dir.path() / file);
  options.config.decoder = decoder;
  options.steps = steps;
  train(options);
  return options;
}

VectorNetConfig kinematicConfig() {
  VectorNetConfig config;
  config.decoder = "kinematic";
  config.horizon = 25;
  config.step = 0.2;
  return config;
}

}  // namespace

TEST(DecoderRegistry, UnknownDecodersAndOptionsAreRejectedWithWhatExists) {
  VectorNetConfig config = kinematicConfig();
  config.decoder = "transformer";
  const auto error = errorOf([&] { config.validate(); });
  EXPECT_NE(error.find("unknown decoder 'transformer' (known: offsets, kinematic)"), std::string::npos) << error;
  config.decoder = "offsets";
  config.decoderOptions = {{"max_accel", 3.0}};
  EXPECT_NE(errorOf([&] { config.validate(); }).find("decoder 'offsets' has no option 'max_accel' (its options: residual)"),
            std::string::npos);
  config.decoderOptions = {{"residual", 2.0}};
  EXPECT_NE(errorOf([&] { config.validate(); }).find("residual"), std::string::npos);
  EXPECT_THROW(parseDecoderOptions({"residual"}), ConfigError);
  EXPECT_THROW(parseDecoderOptions({"residual=maybe"}), ConfigError);
  EXPECT_EQ(parseDecoderOptions({"residual=false", "nll=1"}), (std::map<std::string, double>{{"nll", 1.0}, {"residual", 0.0}}));
}

TEST(Kinematics, RolloutIsTheSimulatorsVehicleModel) {
  // Random controls, including braking to a standstill and restarting; the simulator's
  // update (sim/vehicle_model.cpp) in double precision is the reference.
  std::mt19937 engine(7);
  std::uniform_real_distribution<double> accel(-9.0, 4.0);
  std::uniform_real_distribution<double> curvature(-0.05, 0.05);
  const int steps = 25;
  const double dt = 0.2;
  for (const double initial_speed : {0.0, 3.0, 15.0}) {
    std::vector<float> a(steps);
    std::vector<float> k(steps);
    for (int i = 0; i < steps; ++i) {
      a[static_cast<std::size_t>(i)] = static_cast<float>(accel(engine));
      k[static_cast<std::size_t>(i)] = static_cast<float>(curvature(engine));
    }
    const auto path = rollout(torch::tensor({{1.0F, -2.0F}}), torch::tensor({0.3F}),
                              torch::tensor({static_cast<float>(initial_speed)}), torch::tensor(a).view({1, steps}),
                              torch::tensor(k).view({1, steps}), dt);
    VehicleState state{1.0, -2.0, 0.3, initial_speed, 0.0};
    for (int i = 0; i < steps; ++i) {
      state = sim::advanceKinematic(state, {a[static_cast<std::size_t>(i)], k[static_cast<std::size_t>(i)]}, dt, 0.0);
      EXPECT_NEAR(path.positions[0][i][0].item<float>(), state.x, 2e-4);
      EXPECT_NEAR(path.positions[0][i][1].item<float>(), state.y, 2e-4);
      EXPECT_NEAR(path.speeds[0][i].item<float>(), state.speed, 1e-4);
      EXPECT_NEAR(path.accels[0][i].item<float>(), state.accel, 1e-3);
      EXPECT_NEAR(path.headings[0][i].item<float>(), state.heading, 1e-4);
    }
  }
}

namespace {

/// The linearisation of a rollout (`roll(accel, lateral control)`) against one-sided finite
/// differences of its positions, for a few controls.
void expectSensitivitiesMatchFiniteDifferences(const std::function<Rollout(const torch::Tensor&, const torch::Tensor&)>& roll,
                                               const torch::Tensor& accel, const torch::Tensor& lateral, double dt,
                                               double h) {
  const auto base = roll(accel, lateral);
  const auto sens = sensitivities(base, dt);
  const auto steps = accel.size(1);
  for (const int j : {0, 5, 11}) {
    auto a = accel.clone();
    a[0][j] += h;
    const auto da = (roll(a, lateral).positions - base.positions) / h;
    auto c = lateral.clone();
    c[0][j] += h;
    const auto dc = (roll(accel, c).positions - base.positions) / h;
    for (int k = 0; k < steps; ++k) {
      for (int x = 0; x < 2; ++x) {
        const double numeric_a = da[0][k][x].item<double>();
        const double numeric_c = dc[0][k][x].item<double>();
        EXPECT_NEAR(sens.accel[0][k][j][x].item<double>(), numeric_a, 1e-4 * (1.0 + std::abs(numeric_a))) << k << j;
        EXPECT_NEAR(sens.curvature[0][k][j][x].item<double>(), numeric_c, 1e-4 * (1.0 + std::abs(numeric_c))) << k << j;
      }
    }
  }
}

}  // namespace

TEST(Kinematics, SensitivitiesMatchFiniteDifferences) {
  const int steps = 12;
  const double dt = 0.2;
  auto accel = torch::linspace(-1.0, 1.0, steps, torch::kFloat64).view({1, steps});
  auto curvature = torch::linspace(0.02, -0.01, steps, torch::kFloat64).view({1, steps});
  const auto position = torch::zeros({1, 2}, torch::kFloat64);
  const auto heading = torch::full({1}, 0.4, torch::kFloat64);
  const auto speed = torch::full({1}, 10.0, torch::kFloat64);
  expectSensitivitiesMatchFiniteDifferences(
      [&](const torch::Tensor& a, const torch::Tensor& c) { return rollout(position, heading, speed, a, c, dt); }, accel,
      curvature, dt, 1e-5);
}

TEST(Kinematics, HeadingControlMovesAlongEachStepsHeadingAndItsSensitivitiesMatchFiniteDifferences) {
  const int steps = 12;
  const double dt = 0.2;
  auto accel = torch::linspace(-3.0, 1.0, steps, torch::kFloat64).view({1, steps});
  auto heading = torch::linspace(0.2, -0.3, steps, torch::kFloat64).view({1, steps});
  const auto position = torch::tensor({{1.0, -2.0}}, torch::kFloat64);
  const auto speed = torch::full({1}, 6.0, torch::kFloat64);
  const auto base = rolloutHeadings(position, speed, accel, heading, dt);
  // Each step goes straight along its heading for the trapezoid's distance; speeds and
  // accelerations are those of the curvature rollout (the same longitudinal model).
  const auto curved = rollout(position, torch::zeros({1}, torch::kFloat64), speed, accel, torch::zeros_like(accel), dt);
  Vec2 p(1.0, -2.0);
  for (int k = 0; k < steps; ++k) {
    const double s = curved.distances[0][k].item<double>();
    p += s * headingVector(heading[0][k].item<double>());
    EXPECT_NEAR(base.positions[0][k][0].item<double>(), p.x(), 1e-9);
    EXPECT_NEAR(base.positions[0][k][1].item<double>(), p.y(), 1e-9);
    EXPECT_NEAR(base.speeds[0][k].item<double>(), curved.speeds[0][k].item<double>(), 1e-12);
    EXPECT_NEAR(base.headings[0][k].item<double>(), heading[0][k].item<double>(), 1e-12);
  }
  expectSensitivitiesMatchFiniteDifferences(
      [&](const torch::Tensor& a, const torch::Tensor& c) { return rolloutHeadings(position, speed, a, c, dt); }, accel,
      heading, dt, 1e-6);
}

namespace {

/// Moderate noise: the decoder's linearised position covariance equals the sample
/// covariance of its rollouts.
void expectCovarianceOfSamples(const Decoder& decoder) {
  auto raw = torch::zeros({1, decoder.outputWidth()});
  raw.narrow(1, 0, 25).fill_(-0.5);
  raw.narrow(1, 25, 25).fill_(1.0);
  raw.narrow(1, 50, 52).fill_(-2.5);
  EgoStart one{torch::zeros({1, 2}), torch::zeros({1}), torch::tensor({10.0F})};
  const auto distribution = decoder.decode(raw, one);
  torch::manual_seed(3);
  const auto samples = decoder.sample(distribution, one, torch::randn({1, 20000, decoder.noiseWidth()}));
  for (const int k : {4, 14, 24}) {
    const auto points = samples.positions[0].select(1, k);  // [S, 2]
    const auto centred = points - points.mean(0);
    const auto empirical = centred.t().mm(centred) / static_cast<double>(points.size(0) - 1);
    // Less the floor every position's variance has (float32 targets), which samples do not draw.
    const auto predicted = distribution.covariance[0][k] - 0.02 * 0.02 * torch::eye(2);
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 2; ++c) {
        const double scale = std::sqrt(predicted[r][r].item<float>() * predicted[c][c].item<float>());
        EXPECT_NEAR(empirical[r][c].item<float>(), predicted[r][c].item<float>(), 0.1 * scale) << k << " " << r << c;
      }
    }
  }
}

}  // namespace

TEST(KinematicDecoder, ControlsAreBoundedAndTheCovarianceIsThatOfItsSamples) {
  auto config = kinematicConfig();
  config.decoderOptions = {{"heading_control", 0.0}};  // curvature control
  const auto decoder = makeDecoder(config);
  ASSERT_EQ(decoder->outputWidth(), 4 * 25 + 2);
  EgoStart start{torch::zeros({2, 2}), torch::zeros({2}), torch::tensor({12.0F, 3.0F})};
  // Absurd raw outputs: the controls saturate at the limits, the Ego never reverses.
  auto raw = torch::zeros({2, decoder->outputWidth()});
  raw.narrow(1, 0, 25).fill_(-1000.0);
  raw.narrow(1, 25, 25).fill_(1000.0);
  raw.narrow(1, 50, 52).fill_(-20.0);  // tiny standard deviations
  const auto decoded = decoder->decode(raw, start);
  EXPECT_GE(decoded.accels.min().item<float>(), -9.0F - 1e-3F);
  EXPECT_GE(decoded.speeds.min().item<float>(), 0.0F);
  // 12 m/s at -9 m/s^2 stops after 1.33 s, 8 m along a circle of radius 4 m (kappa 0.25 1/m).
  const auto path = torch::cat({torch::zeros({1, 2}), decoded.positions[0]}, 0);
  EXPECT_NEAR((path.narrow(0, 1, 25) - path.narrow(0, 0, 25)).norm(2, 1).sum().item<float>(), 12.0 * 12.0 / 18.0, 0.05);
  EXPECT_NEAR(decoded.headings[0][24].item<float>(), 0.25 * 8.0, 0.02);
  expectCovarianceOfSamples(*decoder);
}

TEST(KinematicDecoder, HeadingControlIsTheDefaultBoundedToMaxHeadingWithTheCovarianceOfItsSamples) {
  auto config = kinematicConfig();
  config.decoderOptions = {{"max_heading", 0.5}};
  const auto decoder = makeDecoder(config);
  EgoStart start{torch::zeros({1, 2}), torch::zeros({1}), torch::tensor({12.0F})};
  auto raw = torch::zeros({1, decoder->outputWidth()});
  raw.narrow(1, 25, 25).fill_(1000.0);  // every step as far left as allowed
  raw.narrow(1, 50, 52).fill_(-20.0);
  const auto decoded = decoder->decode(raw, start);
  for (int k = 0; k < 25; ++k) EXPECT_NEAR(decoded.headings[0][k].item<float>(), 0.5F, 1e-4F);
  // A straight line at 0.5 rad: 12 m/s for 5 s.
  EXPECT_NEAR(decoded.positions[0][24][0].item<float>(), 60.0F * std::cos(0.5F), 1e-2F);
  EXPECT_NEAR(decoded.positions[0][24][1].item<float>(), 60.0F * std::sin(0.5F), 1e-2F);
  expectCovarianceOfSamples(*decoder);
}

TEST(KinematicDecoder, TheAccelerationLossComparesWithTheAccelerationsOfTheTruePositions) {
  auto config = kinematicConfig();
  config.decoderOptions = {{"nll", 0.0}};
  const auto plain = makeDecoder(config);
  config.decoderOptions["accel_weight"] = 1.0;
  const auto weighted = makeDecoder(config);
  EgoStart start{torch::zeros({1, 2}), torch::zeros({1}), torch::tensor({10.0F})};
  auto raw = torch::zeros({1, plain->outputWidth()});
  raw.narrow(1, 0, 10).fill_(-2.0);  // brakes, then holds its speed, straight ahead
  const auto decoded = weighted->decode(raw, start);
  const auto mask = torch::ones({1, 25}, torch::kBool);
  // The true future is the predicted one: nothing to learn.
  EXPECT_NEAR(weighted->loss(decoded, decoded.positions.clone(), mask).item<float>(), 0.0F, 1e-3F);
  // The true Ego kept its speed: the predicted decelerations are the error.
  const auto kept = torch::arange(1, 26, torch::kFloat32).unsqueeze(-1) * torch::tensor({2.0F, 0.0F});
  const float ade = plain->loss(plain->decode(raw, start), kept.unsqueeze(0), mask).item<float>();
  const float mean_decel = -decoded.accels.mean().item<float>();
  EXPECT_GT(mean_decel, 0.5F);
  EXPECT_NEAR(weighted->loss(decoded, kept.unsqueeze(0), mask).item<float>(), ade + mean_decel, 1e-3F);
}

TEST(KinematicDecoder, TheMinimumAccelerationLossComparesTheMinimaOverValidSteps) {
  auto config = kinematicConfig();
  config.decoderOptions = {{"nll", 0.0}};
  const auto plain = makeDecoder(config);
  config.decoderOptions["amin_weight"] = 1.0;
  const auto weighted = makeDecoder(config);
  EgoStart start{torch::zeros({1, 2}), torch::zeros({1}), torch::tensor({10.0F})};
  auto raw = torch::zeros({1, plain->outputWidth()});
  raw.narrow(1, 0, 10).fill_(-2.0);   // brakes for 2 s ...
  raw.narrow(1, 20, 5).fill_(-3.0);   // ... and harder at the end
  const auto decoded = weighted->decode(raw, start);
  auto mask = torch::ones({1, 25}, torch::kBool);
  EXPECT_NEAR(weighted->loss(decoded, decoded.positions.clone(), mask).item<float>(), 0.0F, 1e-3F);
  // The true Ego kept its speed (a_min 0): the error is the predicted minimum.
  const auto kept = (torch::arange(1, 26, torch::kFloat32).unsqueeze(-1) * torch::tensor({2.0F, 0.0F})).unsqueeze(0);
  const float ade = plain->loss(plain->decode(raw, start), kept, mask).item<float>();
  const float predicted_min = decoded.accels.min().item<float>();
  EXPECT_LT(predicted_min, -2.5F);
  EXPECT_NEAR(weighted->loss(decoded, kept, mask).item<float>(), ade - predicted_min, 1e-3F);
  // Steps after an invalid position do not count: the hard braking at the end is left out.
  mask.narrow(1, 15, 10).fill_(false);
  const float ade_valid = plain->loss(plain->decode(raw, start), kept, mask).item<float>();
  const float valid_min = decoded.accels.narrow(1, 0, 15).min().item<float>();
  EXPECT_GT(valid_min, -2.5F);
  EXPECT_NEAR(weighted->loss(decoded, kept, mask).item<float>(), ade_valid - valid_min, 1e-3F);
}

TEST(KinematicDecoder, CalibrationScalesTheVariancesUntilNinetyPercentAreCovered) {
  auto config = kinematicConfig();
  config.hidden = 16;
  config.globalWidth = 16;
  config.decoderHidden = 32;
  torch::manual_seed(2);
  Model model = Model::create(config);
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 200; ++i) scenes.push_back(syntheticScene(i));
  const auto tensors = buildTensors(scenes, config);
  const auto before = coverage90(model, tensors);
  const auto covariance = model.decode(tensors.select(torch::arange(0, 1))).covariance;
  const auto fitted = calibrateVariance(model, tensors);
  EXPECT_NEAR(fitted.coverageBefore, before, 1e-9);
  EXPECT_GT(std::abs(fitted.scale - 1.0), 0.05);
  EXPECT_NEAR(fitted.coverageAfter, 0.9, 0.02);
  EXPECT_NEAR(coverage90(model, tensors), fitted.coverageAfter, 1e-9);
  EXPECT_EQ(model.config.decoderOption("variance_scale"), fitted.scale);
  // Every control variance is multiplied by the scale: the covariances follow, up to the
  // position floor (0.02 m)^2 that does not scale.
  const auto scaled = model.decode(tensors.select(torch::arange(0, 1))).covariance;
  const auto floor = 0.02 * 0.02 * torch::eye(2);
  EXPECT_TRUE(torch::allclose(scaled - floor, fitted.scale * (covariance - floor), 1e-3, 1e-6));
}

TEST(GaussianNll, IsTheTwoDimensionalNormalDensity) {
  const auto mean = torch::tensor({{{1.0F, 2.0F}}});
  auto covariance = torch::tensor({{{{4.0F, 1.0F}, {1.0F, 2.0F}}}});
  const auto target = torch::tensor({{{2.0F, 1.0F}}});
  // r = (1, -1); S^-1 = [[2, -1], [-1, 4]] / 7; r' S^-1 r = (2 + 2 + 4) / 7.
  const double expected = 0.5 * 8.0 / 7.0 + 0.5 * std::log(7.0) + std::log(2.0 * kPi);
  EXPECT_NEAR(gaussianNll(mean, covariance, target).item<float>(), expected, 1e-5);
}

// --- model files ---------------------------------------------------------------------

TEST(ModelFiles, ModelFilesFromBeforeDecodersLoadAsOffsetsWithTheResidual) {
  // Written by vsd-sumo 44f90ac (format vsd-model/1): a tiny model, 8 acc scenes and what
  // that version predicted for them.
  const fs::path legacy = sourceDir() / "tests" / "model" / "data" / "legacy_v1";
  const Predictor predictor(legacy / "model.pt");
  EXPECT_EQ(predictor.name(), "offsets");
  EXPECT_EQ(predictor.info().config.decoderOption("residual"), 1.0);
  EXPECT_EQ(predictor.info().config.frame, "ego");
  EXPECT_FALSE(predictor.probabilistic());
  const vector::DatasetReader reader(legacy / "scenes.h5");
  std::vector<vector::VectorizedScene> scenes;
  for (std::size_t i = 0; i < reader.size(); ++i) scenes.push_back(reader.scene(i));
  const auto predictions = predictor.predict(scenes);
  H5::H5File file((legacy / "predictions.h5").string(), H5F_ACC_RDONLY);
  const auto expected = h5::readAll<double>(file.openDataSet("predictions"));
  ASSERT_EQ(expected.size(), scenes.size() * 25 * 2);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    for (std::size_t k = 0; k < 25; ++k) {
      EXPECT_NEAR(predictions[i][k].x(), expected[(i * 25 + k) * 2], 1e-4);
      EXPECT_NEAR(predictions[i][k].y(), expected[(i * 25 + k) * 2 + 1], 1e-4);
    }
  }
}

TEST(ModelFiles, AModelOfAnUnknownDecoderIsRefusedWithTheKnownOnes) {
  TemporaryDirectory dir;
  const fs::path legacy = sourceDir() / "tests" / "model" / "data" / "legacy_v1";
  auto options = tinyTraining(legacy / "scenes.h5", dir.path() / "m.pt");
  options.steps = 2;
  train(options);
  const auto foreign = dir.path() / "foreign.pt";
  // The description is a length-prefixed string inside the archive: keep the length.
  ASSERT_TRUE(rewriteModelDescription(options.output, foreign, R"("name":"offsets")", R"("name":"mystery")"));
  const auto error = errorOf([&] { Predictor predictor(foreign); });
  EXPECT_NE(error.find("foreign.pt"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown decoder 'mystery' (known: offsets, kinematic)"), std::string::npos) << error;
}

TEST(ModelFiles, KinematicModelsOfFormatTwoKeepCurvatureControl) {
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", 20), dir.path() / "k.pt");
  options.config.decoder = "kinematic";
  options.steps = 2;
  train(options);
  EXPECT_EQ(Predictor(options.output).info().config.decoderOption("heading_control"), 1.0);  // today's default
  // Written before heading control existed: the options are absent and it meant curvature control.
  const auto older = dir.path() / "older.pt";
  ASSERT_TRUE(rewriteModelDescription(options.output, older,
                                      "d['format'] = 'vsd-model/2'\n"
                                      "for name in ('heading_control', 'max_heading', 'accel_nll'):\n"
                                      "    del d['decoder']['options'][name]"));
  EXPECT_EQ(Predictor(older).info().config.decoderOption("heading_control"), 0.0);
}

TEST(ModelFiles, LaneFrameModelsRecordTheirSmoothingAndFormatThreeMeantFourMetres) {
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", 20), dir.path() / "lane.pt");
  options.config.decoder = "kinematic";
  options.config.frame = "lane";
  options.config.laneSmoothing = 2.5;
  options.steps = 2;
  train(options);
  EXPECT_EQ(Predictor(options.output).info().config.laneSmoothing, 2.5);
  EXPECT_EQ(VectorNetConfig{}.laneSmoothing, 3.0);  // README "Lane frame smoothing"
  const auto older = dir.path() / "older.pt";
  ASSERT_TRUE(rewriteModelDescription(options.output, older,
                                      "d['format'] = 'vsd-model/3'\n"
                                      "del d['config']['lane_smoothing']"));
  EXPECT_EQ(Predictor(older).info().config.laneSmoothing, 4.0);
  options.config.laneSmoothing = 0.0;
  try {
    train(options);
    ADD_FAILURE() << "trained with no smoothing";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("--lane-smoothing"), std::string::npos) << error.what();
  }
}

// --- predictors without training ---------------------------------------------------------

namespace {

/// An Ego braking at a constant 2 m/s^2 from 12 m/s, with `history` steps before t0.
vector::VectorizedScene brakingScene(std::size_t history) {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  VehicleState state{3.0, 4.0, 0.5, 12.0, 0.0};
  for (std::size_t k = 0; k < history + 26; ++k) {
    ego.states.push_back(state);
    ego.valid.push_back(1);
    state = sim::advanceKinematic(state, {-2.0, 0.0}, 0.2, 0.0);
  }
  trace.vehicles = {ego};
  return vector::buildScene("braking", trace, history, {});
}

}  // namespace

TEST(Predictors, ConstantVelocityAndConstantAccelerationNeedNoTraining) {
  const Predictor cv("cv");
  const Predictor ca("ca");
  EXPECT_FALSE(cv.info().trained);
  EXPECT_TRUE(ca.predictsMotion());
  EXPECT_TRUE(Predictor::isBuiltin("cv"));
  EXPECT_FALSE(Predictor::isBuiltin("models/cv.pt"));
  // With two steps of history, ca knows the deceleration and predicts the future exactly.
  const auto with_history = brakingScene(2);
  const auto exact = ca.predictDistribution({with_history}, {}).front();
  for (std::size_t k = 0; k < 25; ++k) {
    EXPECT_LT((exact.mostLikely.positions[k] - with_history.target[k]).norm(), 2e-3) << k;
    EXPECT_NEAR(exact.mostLikely.states[k].accel, -2.0, 1e-3);
  }
  // cv keeps the initial speed along the initial heading.
  const auto straight = cv.predictDistribution({with_history}, {}).front();
  const auto initial = with_history.egoInitialState();
  for (std::size_t k = 0; k < 25; ++k) {
    const Vec2 expected = initial.position() + 0.2 * static_cast<double>(k + 1) * initial.speed * headingVector(initial.heading);
    EXPECT_LT((straight.mostLikely.positions[k] - expected).norm(), 2e-3);
    EXPECT_NEAR(straight.mostLikely.states[k].speed, initial.speed, 1e-4);
  }
  // Without history (generated scenes), ca has no acceleration to go on: it is cv.
  const auto no_history = brakingScene(0);
  const auto a = ca.predict({no_history}).front();
  const auto c = cv.predict({no_history}).front();
  for (std::size_t k = 0; k < 25; ++k) EXPECT_LT((a[k] - c[k]).norm(), 1e-9);
}

// --- sampling -----------------------------------------------------------------------------

TEST(KinematicModel, PredictionsAreDrivableCarryTheirOwnKinematicsAndSampleReproducibly) {
  TemporaryDirectory dir;
  auto training = tinyTraining(writeDataset(dir.path() / "acc.h5", 40), dir.path() / "k.pt");
  training.config.decoder = "kinematic";
  train(training);
  const Predictor predictor(training.output);
  EXPECT_EQ(predictor.name(), "kinematic");
  EXPECT_TRUE(predictor.probabilistic());
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 6; ++i) scenes.push_back(syntheticScene(i));
  PredictOptions options;
  options.samples = 16;
  const auto predictions = predictor.predictDistribution(scenes, options);
  const metrics::MetricSet a_min({"a_min"}, pipeline::sceneAvailability("generated"), "test");
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const auto& p = predictions[i];
    ASSERT_EQ(p.mostLikely.states.size(), 25u);
    ASSERT_EQ(p.samples.size(), 16u);
    ASSERT_EQ(p.positionCovariance.size(), 25u);
    double previous = scenes[i].egoInitialState().speed;
    for (const auto& state : p.mostLikely.states) {
      EXPECT_GE(state.speed, 0.0);
      EXPECT_NEAR(state.accel, (state.speed - previous) / 0.2, 1e-3);
      EXPECT_GE(state.accel, -9.0 - 1e-3);
      EXPECT_LE(state.accel, 4.0 + 1e-3);
      previous = state.speed;
    }
    for (const auto& sample : p.samples) {
      for (const auto& state : sample.states) EXPECT_GE(state.speed, 0.0);
    }
    EXPECT_GT(p.positionCovariance.back().determinant(), 0.0);
    // a_min of the prediction is the minimum of its own accelerations (none reconstructed from positions).
    double lowest = p.mostLikely.states.front().accel;
    for (const auto& state : p.mostLikely.states) lowest = std::min(lowest, state.accel);
    EXPECT_DOUBLE_EQ(pipeline::metricsOfFuture(a_min, scenes[i], p.mostLikely.states).front(), lowest);
  }

  // A scene's samples depend on the seed and the scene, not on the batch it is in.
  options.samples = 8;
  options.seed = 3;
  const auto alone = predictor.predictDistribution({syntheticScene(7)}, options).front();
  const auto batched = predictor.predictDistribution({syntheticScene(2), syntheticScene(7), syntheticScene(9)}, options)[1];
  double largest = 0.0;
  for (std::size_t s = 0; s < 8; ++s) {
    for (std::size_t k = 0; k < 25; ++k) {
      largest = std::max(largest, (alone.samples[s].positions[k] - batched.samples[s].positions[k]).norm());
    }
  }
  EXPECT_LT(largest, 1e-4);
  options.seed = 4;
  const auto reseeded = predictor.predictDistribution({syntheticScene(7)}, options).front();
  EXPECT_GT((reseeded.samples[0].positions.back() - alone.samples[0].positions.back()).norm(), 1e-4);
  options.samples = -1;
  EXPECT_NE(errorOf([&] { predictor.predictDistribution({syntheticScene(7)}, options); }).find("--samples"),
            std::string::npos);
}

TEST(KinematicModel, ADivergingTrainingStopsWithTheStepAndKeepsTheLastGoodModel) {
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", 40), dir.path() / "d.pt");
  options.config.decoder = "kinematic";
  options.steps = 50;
  installInterruptHandlers();
  int epochs_seen = 0;
  EXPECT_THROW(train(options, [&](const EpochRecord&) {
                 if (++epochs_seen == 3) std::raise(SIGINT);
               }),
               InterruptedError);
  clearInterruption();
  const std::string good_model = readTextFile(options.output);
  const std::string good_state = readTextFile(options.output.string() + ".last");
  options.resume = true;
  options.learningRate = 10.0;  // the largest rate allowed: the next steps blow the variances up
  const auto error = errorOf([&] { train(options); });
  EXPECT_NE(error.find("training diverged at optimizer step"), std::string::npos) << error;
  EXPECT_NE(error.find("batch"), std::string::npos) << error;
  EXPECT_NE(error.find("keeps the last good model"), std::string::npos) << error;
  EXPECT_EQ(readTextFile(options.output), good_model);
  EXPECT_EQ(readTextFile(options.output.string() + ".last"), good_state);
}

TEST(KinematicModel, CalibrateFitsTheVarianceScaleAfterTrainingAndStoresItInTheModelFile) {
  TemporaryDirectory dir;
  auto options = trainTiny(dir, "kinematic", 60, 12, "k.pt");
  const Predictor plain(options.output);
  EXPECT_EQ(plain.info().config.decoderOption("variance_scale"), 1.0);
  const auto before = plain.predictDistribution({syntheticScene(3)}, {}).front();
  // The same training with calibrate=1 (same seed: the same weights) also fits the scale.
  options.output = dir.path() / "calibrated.pt";
  options.config.decoderOptions["calibrate"] = 1.0;
  train(options);
  const Predictor calibrated(options.output);
  const double scale = calibrated.info().config.decoderOption("variance_scale");
  EXPECT_GT(std::abs(scale - 1.0), 0.01);
  const auto after = calibrated.predictDistribution({syntheticScene(3)}, {}).front();
  EXPECT_LT((after.mostLikely.positions.back() - before.mostLikely.positions.back()).norm(), 1e-6);
  const Eigen::Matrix2d floor = 0.02 * 0.02 * Eigen::Matrix2d::Identity();
  EXPECT_NEAR((after.positionCovariance.back() - floor).trace(), scale * (before.positionCovariance.back() - floor).trace(),
              1e-3 * scale * before.positionCovariance.back().trace());
}

TEST(KinematicModel, CalibrateFitsConformalPositionRegionsAndMetricIntervalsThatPredictionsCarry) {
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", 80), dir.path() / "k.pt");
  options.config.decoder = "kinematic";
  options.config.decoderOptions = {{"heading_control", 1.0}, {"calibrate", 1.0}};
  options.steps = 12;
  options.validationFraction = 0.5;  // 40 held-out scenes: enough for a calibration
  auto metric_set = std::make_shared<const metrics::MetricSet>(std::vector<std::string>{"a_min", "d_min"},
                                                               pipeline::sceneAvailability("generated"), "test");
  auto binding = std::make_shared<MetricBinding>();
  binding->names = metric_set->names();
  binding->compute = [metric_set](const vector::VectorizedScene& scene, const Trajectory& future) {
    return pipeline::metricsOfFuture(*metric_set, scene, future.positions, future.states);
  };
  options.metrics = binding;
  train(options);

  const Predictor calibrated(options.output);
  const auto& info = calibrated.info();
  // Radii per step for the label and pooled, nested, fitted on the 40 held-out scenes.
  ASSERT_NE(info.positionRegions.find("acc"), nullptr);
  EXPECT_EQ(info.positionRegions.scenes, 40u);
  const auto& radii = *info.positionRegions.find("acc");
  ASSERT_EQ(radii.size(), 25u);
  for (const auto& radius : radii) {
    EXPECT_GT(radius[0], 0.0);
    EXPECT_LE(radius[0], radius[1]);
  }
  // The held-out positions lie inside their calibrated regions in the nominal share (at least).
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 40; ++i) scenes.push_back(syntheticScene(i));
  const auto predictions = calibrated.predictDistribution(scenes, {});
  ASSERT_EQ(predictions.front().regionRadius2.size(), 25u);
  EXPECT_EQ(predictions.front().regionRadius2[24][1], radii[24][1]);
  // Metric intervals for both metrics, looked up by label (pooled for an unknown one).
  for (const std::string metric : {"a_min", "d_min"}) {
    const auto* widening = info.metricIntervals.find("acc", metric);
    ASSERT_NE(widening, nullptr) << metric;
    EXPECT_EQ(widening->scenes, 40u);
    EXPECT_EQ(widening->levels.size(), kCalibratedLevels.size());
    EXPECT_NE(info.metricIntervals.find("a map", metric), nullptr);
  }
  // They reach predict's file: the region radii of every step.
  const auto predictions_file = dir.path() / "p.h5";
  writePredictions(calibrated, options.output, dir.path() / "acc.h5", predictions_file);
  H5::H5File file(predictions_file.string(), H5F_ACC_RDONLY);
  const auto written = h5::readAll<double>(file.openDataSet("position_region_radius2"));
  ASSERT_EQ(written.size(), 80u * 25u * 2u);
  EXPECT_EQ(written[24 * 2 + 1], radii[24][1]);

  // A damaged calibration is refused naming the file.
  const auto damaged = dir.path() / "damaged.pt";
  ASSERT_TRUE(rewriteModelDescription(options.output, damaged,
                                      "d['calibration']['metric_intervals']['acc']['a_min']['widening'][0] = 1e9"));
  const auto error = errorOf([&] { Predictor predictor(damaged); });
  EXPECT_NE(error.find("damaged.pt"), std::string::npos) << error;
  EXPECT_NE(error.find("calibration"), std::string::npos) << error;
}

// --- intervals and scores ----------------------------------------------------------------

TEST(Intervals, WeibullQuantilesCoverTheirNominalShareForFewDraws) {
  EXPECT_DOUBLE_EQ(sampleQuantile({3, 1, 2, 5, 4, 7, 6, 9, 8}, 0.5), 5.0);
  EXPECT_DOUBLE_EQ(sampleQuantile({3, 1, 2, 5, 4, 7, 6, 9, 8}, 0.25), 2.5);  // order 0.25 * 10
  EXPECT_DOUBLE_EQ(sampleQuantile({3, 1, 2}, 0.01), 1.0);                     // clamped
  EXPECT_TRUE(std::isnan(sampleQuantile({std::nan("")}, 0.5)));
  // 32 draws and one more value from the same distribution, many times: the central 90 %
  // and 50 % intervals hold the value 90 % and 50 % of the time.
  std::mt19937 engine(11);
  std::normal_distribution<double> normal;
  std::size_t inside90 = 0;
  std::size_t inside50 = 0;
  const std::size_t trials = 20000;
  for (std::size_t t = 0; t < trials; ++t) {
    std::vector<double> draws(32);
    for (auto& d : draws) d = normal(engine);
    const double value = normal(engine);
    const auto interval = intervalOf(draws);
    const double q = quantilePosition(draws, value);
    EXPECT_EQ(interval.contains(value, 0.9), std::abs(2.0 * q - 1.0) <= 0.9 + 1e-12);
    EXPECT_EQ(interval.contains(value, 0.5), std::abs(2.0 * q - 1.0) <= 0.5 + 1e-12);
    inside90 += interval.contains(value, 0.9) ? 1 : 0;
    inside50 += interval.contains(value, 0.5) ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(inside90) / trials, 0.90, 0.01);
  EXPECT_NEAR(static_cast<double>(inside50) / trials, 0.50, 0.015);
}

namespace {

/// Held-out scenes of a metric whose futures are over-confident and biased (or
/// over-cautious): per scene a centre m; 32 draws N(m, spread^2); the true value
/// N(m + bias, truth^2).
std::vector<HeldOutMetric> heldOutMetric(std::size_t scenes, double spread, double bias, double truth,
                                         std::mt19937& engine) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> centre(-3.0, 3.0);
  std::vector<HeldOutMetric> result;
  for (std::size_t i = 0; i < scenes; ++i) {
    HeldOutMetric scene;
    const double m = centre(engine);
    for (int s = 0; s < 32; ++s) scene.draws.push_back(m + spread * normal(engine));
    scene.reference = m + bias + truth * normal(engine);
    result.push_back(scene);
  }
  return result;
}

double coverageOf(const std::vector<HeldOutMetric>& scenes, double level, const IntervalWidening* widening) {
  std::size_t inside = 0;
  for (const auto& scene : scenes) {
    const auto interval = intervalOf(scene.draws, widening);
    inside += interval.contains(scene.reference, level) ? 1 : 0;
    // One number per scene gives the coverage of every level (the reliability diagram).
    EXPECT_EQ(interval.contains(scene.reference, level), containingLevel(scene.draws, scene.reference, widening) <= level);
  }
  return static_cast<double>(inside) / static_cast<double>(scenes.size());
}

}  // namespace

TEST(Intervals, ConformalWideningBringsOverConfidentAndOverCautiousIntervalsToTheirNominalCoverage) {
  std::mt19937 engine(5);
  for (const auto& [spread, bias, truth] : {std::tuple{0.3, 0.4, 0.8}, std::tuple{2.0, 0.0, 0.5}}) {
    const auto held_out = heldOutMetric(1000, spread, bias, truth, engine);
    const auto fresh = heldOutMetric(20000, spread, bias, truth, engine);
    IntervalWidening widening;
    ASSERT_TRUE(fitIntervalWidening(held_out, widening));
    EXPECT_EQ(widening.scenes, 1000u);
    EXPECT_TRUE(std::is_sorted(widening.widening.begin(), widening.widening.end()));
    const double raw90 = coverageOf(fresh, 0.9, nullptr);
    EXPECT_GT(std::abs(raw90 - 0.9), 0.08) << "spread " << spread;  // the draws alone are off
    EXPECT_NEAR(coverageOf(fresh, 0.9, &widening), 0.90, 0.025) << "spread " << spread;
    EXPECT_NEAR(coverageOf(fresh, 0.5, &widening), 0.50, 0.04) << "spread " << spread;
    // Every calibrated level, not only 50 % and 90 %.
    std::size_t inside70 = 0;
    for (const auto& scene : fresh) inside70 += containingLevel(scene.draws, scene.reference, &widening) <= 0.7 ? 1 : 0;
    EXPECT_NEAR(static_cast<double>(inside70) / static_cast<double>(fresh.size()), 0.70, 0.04) << "spread " << spread;
  }
  // Too few usable held-out scenes (NaN references do not count): no calibration.
  auto few = heldOutMetric(kMinCalibrationScenes + 5, 1.0, 0.0, 1.0, engine);
  for (std::size_t i = 0; i < 6; ++i) few[i].reference = std::nan("");
  IntervalWidening untouched;
  EXPECT_FALSE(fitIntervalWidening(few, untouched));
  EXPECT_TRUE(untouched.levels.empty());
  // Lookup: the label's own widening, else the pooled one, else none.
  IntervalCalibration calibration;
  calibration.byLabel[""]["a_min"].floor = 1.0;
  calibration.byLabel["acc"]["a_min"].floor = 2.0;
  EXPECT_EQ(calibration.find("acc", "a_min")->floor, 2.0);
  EXPECT_EQ(calibration.find("lk", "a_min")->floor, 1.0);
  EXPECT_EQ(calibration.find("acc", "d_min"), nullptr);
}

TEST(Calibration, PointsFollowTheHorizon) {
  // The paper's 5 s of 0.2 s steps: 1 s, 3 s, 5 s (target indices 4, 14, 24).
  EXPECT_EQ(calibrationSteps(25), (std::array<std::size_t, kCalibrationPoints>{4, 14, 24}));
  // A 3 s horizon of 0.2 s steps: 0.6 s, 1.8 s, 3 s - the end is always the horizon's.
  EXPECT_EQ(calibrationSteps(15), (std::array<std::size_t, kCalibrationPoints>{2, 8, 14}));
  // A one-step horizon: every point is that step.
  EXPECT_EQ(calibrationSteps(1), (std::array<std::size_t, kCalibrationPoints>{0, 0, 0}));
}

TEST(Calibration, NllAndCoverageOfAPredictedGaussian) {
  auto scene = syntheticScene(3);
  Prediction prediction;
  const double sigma = 0.5;
  for (std::size_t k = 0; k < 25; ++k) {
    // The truth sits 0.3 m (0.6 sigma) beside the mean at every step, 1 m (2 sigma) at 5 s.
    const double offset = k == 24 ? 1.0 : 0.3;
    prediction.mostLikely.positions.push_back(scene.target[k] + Vec2(0.0, offset));
    prediction.positionCovariance.push_back(sigma * sigma * Eigen::Matrix2d::Identity());
  }
  const auto errors = predictionErrors(prediction, scene);
  ASSERT_EQ(errors.scored, 1u);
  const auto nll = [&](double r) { return 0.5 * r * r / (sigma * sigma) + std::log(sigma * sigma) + std::log(2.0 * kPi); };
  EXPECT_NEAR(errors.nll, (24 * nll(0.3) + nll(1.0)) / 25.0, 1e-9);
  EXPECT_NEAR(errors.nllAt[0], nll(0.3), 1e-9);  // 1 s
  EXPECT_NEAR(errors.nllAt[2], nll(1.0), 1e-9);  // 5 s
  // Mahalanobis^2 0.36 at 1 s: inside both regions; 4.0 at 5 s: outside the 50 % region
  // (r'S^-1 r <= 1.39) but inside the 90 % one (<= 4.61).
  EXPECT_EQ(errors.coverageAt[0][0], 1.0);
  EXPECT_EQ(errors.coverageAt[2][0], 0.0);
  EXPECT_EQ(errors.coverageAt[2][1], 1.0);
}

// docs/design.md "Adding a decoder": the decoder's own file plus one registry line, then a
// model trains with it by name and its model file loads and predicts - through the registry
// it was added to; the built-in registry, and so every other user, stays as it was.
TEST(DecoderRegistry, ADecoderAddedFromItsOwnFileTrainsSavesAndLoads) {
  auto decoders = DecoderRegistry::withBuiltins();
  decoders.add(constantAccelDecoderEntry());  // the one line a newcomer writes
  const auto registry = std::make_shared<const DecoderRegistry>(decoders);
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "acc.h5", 20), dir.path() / "ca.pt");
  options.config.decoders = registry;
  options.config.decoder = "constant_accel";
  options.steps = 1;
  train(options);
  const Predictor predictor(options.output, /*threads=*/2, registry);
  EXPECT_EQ(predictor.info().config.decoder, "constant_accel");
  const auto scene = syntheticScene(3);
  const auto predicted = predictor.predict({scene}).at(0);
  ASSERT_EQ(predicted.size(), scene.target.size());
  // Every predicted position lies on the line along the Ego's initial heading.
  const auto start = scene.egoInitialState();
  const Vec2 direction(std::cos(start.heading), std::sin(start.heading));
  for (const auto& p : predicted) {
    const Vec2 r = p - start.position();
    EXPECT_NEAR(r.x() * direction.y() - r.y() * direction.x(), 0.0, 1e-3);
  }
  EXPECT_FALSE(builtinDecoders()->contains("constant_accel"));
  EXPECT_NE(errorOf([&] { Predictor{options.output}; }).find("unknown decoder 'constant_accel' (known: offsets, kinematic)"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { decoders.add(constantAccelDecoderEntry()); }).find("registered twice"), std::string::npos);
  EXPECT_NE(errorOf([&] { decoders.add(DecoderEntry{constantAccelDecoderEntry().info, {}}); }).find("a factory"),
            std::string::npos);
}

TEST(Presets, RecommendedIsTheKinematicConfigurationTheDocsReportAndGivenOptionsAddToIt) {
  VectorNetConfig config;
  applyPreset(findModelPreset("recommended", "--preset"), {{"max_decel", 8.0}, {"accel_weight", 5.0}}, config);
  EXPECT_EQ(config.decoder, "kinematic");
  EXPECT_EQ(config.frame, "lane");
  EXPECT_DOUBLE_EQ(config.decoderOption("calibrate"), 1.0);
  EXPECT_DOUBLE_EQ(config.decoderOption("accel_weight"), 5.0);  // given on top of the preset's 10
  EXPECT_DOUBLE_EQ(config.decoderOption("max_decel"), 8.0);
  EXPECT_NO_THROW(config.validate());
  // Every preset is a valid configuration of the built-in decoders.
  for (const auto& preset : modelPresets()) {
    VectorNetConfig each;
    applyPreset(preset, {}, each);
    EXPECT_NO_THROW(each.validate()) << preset.name;
  }
  EXPECT_NE(errorOf([] { findModelPreset("best", "--preset"); }).find("--preset: unknown preset 'best' (known: recommended, paper)"),
            std::string::npos);
}
