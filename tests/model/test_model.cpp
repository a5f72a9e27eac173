// VectorNet: tensors and masks, invariances, frames, training, checkpoints, bad input.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <csignal>
#include <cmath>

#include "../../src/model/tensors.hpp"
#include "synthetic_scenes.hpp"
#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/model/model.hpp"
#include "vsd/vector/vectorize.hpp"

using namespace vsd;
using namespace vsd::model;
using namespace vsd::test;
namespace fs = std::filesystem;

namespace {

double maxDifference(const std::vector<Polyline>& a, const std::vector<Polyline>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t k = 0; k < a[i].size(); ++k) worst = std::max(worst, (a[i][k] - b[i][k]).norm());
  }
  return worst;
}

class ModelTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = writeDataset(dir_.path() / "acc.h5", 40);
    auto options = tinyTraining(data_, dir_.path() / "m.pt");
    train(options);
    model_ = options.output;
  }
  TemporaryDirectory dir_;
  fs::path data_;
  fs::path model_;
};

}  // namespace

/// The configuration of paper-sized data (what training takes from a dataset header).
VectorNetConfig paperConfig() {
  VectorNetConfig config;
  config.horizon = 25;
  config.step = 0.2;
  return config;
}

TEST(ModelTensors, ShapesMasksAndTheEgoFrame) {
  const VectorNetConfig config = paperConfig();
  std::vector<vector::VectorizedScene> scenes = {syntheticScene(1), syntheticScene(2)};
  scenes[1].polylines[2].valid[3] = 0;  // one masked leader vector
  const auto tensors = buildTensors(scenes, config);
  // Lanes (2) and the leader are "other" polylines; the Ego has its own tensor.
  EXPECT_EQ(tensors.features.sizes(), (std::vector<std::int64_t>{2, 3, 25, kInputFeatures}));
  EXPECT_EQ(tensors.egoFeatures.sizes(), (std::vector<std::int64_t>{2, 1, 1, kInputFeatures}));
  // Per scene: two lane boundaries of 1 vector each (2-point centre line) and 25 leader vectors.
  EXPECT_EQ(tensors.vectorMask.sum().item<std::int64_t>(), 2 * (1 + 1 + 25) - 1);
  EXPECT_FALSE(tensors.vectorMask[1][2][3].item<bool>());
  EXPECT_TRUE(tensors.polylineMask.all().item<bool>());
  // The Ego's initial vector starts at the origin and points along +x, speed * dt long.
  const auto ego = tensors.egoFeatures[0][0][0];
  EXPECT_NEAR(ego[0].item<float>(), 0.0, 1e-6);
  EXPECT_NEAR(ego[1].item<float>(), 0.0, 1e-6);
  EXPECT_NEAR(static_cast<double>(ego[2].item<float>()) * config.coordinateScale, 9.0 * 0.2, 1e-4);
  EXPECT_NEAR(ego[3].item<float>(), 0.0, 1e-5);
  EXPECT_EQ(ego[6].item<float>(), 1.0F);  // one-hot: Ego
  // The Ego starts at the frame's origin, heading along +x, with its speed.
  EXPECT_NEAR(tensors.start.position.abs().max().item<float>(), 0.0, 1e-6);
  EXPECT_NEAR(tensors.start.heading[0].item<float>(), 0.0, 1e-6);
  EXPECT_NEAR(tensors.start.speed[0].item<float>(), 9.0, 1e-5);
}

TEST(ModelTensors, EgoFrameRoundTrip) {
  const VectorNetConfig config = paperConfig();
  const std::vector<vector::VectorizedScene> scenes = {syntheticScene(3), syntheticScene(11)};
  const auto tensors = buildTensors(scenes, config);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const auto targets = tensors.targets[static_cast<std::int64_t>(i)];
    for (std::size_t k = 0; k < scenes[i].target.size(); ++k) {
      const auto model_point = targets[static_cast<std::int64_t>(k)];
      const Vec2 back = tensors.frames[i]->toScene({model_point[0].item<float>(), model_point[1].item<float>()});
      EXPECT_LT((back - scenes[i].target[k]).norm(), 1e-4);
    }
  }
}

TEST(ModelTensors, NonFiniteFeaturesAreRejectedWithTheSample) {
  auto scene = syntheticScene(4);
  scene.polylines[2].vectors[5][2] = std::nan("");
  try {
    buildTensors({scene}, paperConfig());
    FAIL();
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("sample 4"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("non-finite"), std::string::npos) << error.what();
  }
}

TEST_F(ModelTest, PaddingDoesNotChangeAPrediction) {
  const Predictor predictor(model_);
  const auto alone = predictor.predict({syntheticScene(7)});
  // In a batch with a much larger scene (more polylines and vectors: more padding).
  auto big = syntheticScene(8);
  for (int extra = 0; extra < 5; ++extra) big.polylines.insert(big.polylines.begin(), big.polylines[0]);
  big.polylines[0].vectors.resize(40, big.polylines[0].vectors.back());
  big.polylines[0].valid.resize(40, 1);
  big.egoPolyline += 5;
  vector::numberPolylines(big);
  const auto batched = predictor.predict({big, syntheticScene(7), big});
  EXPECT_LT(maxDifference(alone, {batched[1]}), 1e-4);
}

TEST_F(ModelTest, PermutingPolylinesDoesNotChangeAPrediction) {
  const Predictor predictor(model_);
  auto scene = syntheticScene(9);
  const auto reference = predictor.predict({scene});
  // Ego first, then the leader, then the lanes in reverse order.
  auto permuted = scene;
  permuted.polylines = {scene.polylines[3], scene.polylines[2], scene.polylines[1], scene.polylines[0]};
  permuted.egoPolyline = 0;
  vector::numberPolylines(permuted);
  EXPECT_LT(maxDifference(reference, predictor.predict({permuted})), 1e-4);
}

TEST_F(ModelTest, CheckpointRoundTripGivesIdenticalPredictions) {
  const Predictor first(model_);
  fs::copy_file(model_, dir_.path() / "copy.pt");
  const Predictor second(dir_.path() / "copy.pt");
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 10; ++i) scenes.push_back(syntheticScene(i));
  EXPECT_EQ(maxDifference(first.predict(scenes), second.predict(scenes)), 0.0);
  EXPECT_EQ(first.info().labels, std::vector<std::string>{"acc"});
  EXPECT_EQ(first.info().config.hidden, 16);
}

TEST_F(ModelTest, SameSeedAndThreadsGiveTheSameModel) {
  auto options = tinyTraining(data_, dir_.path() / "again.pt");
  train(options);
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 10; ++i) scenes.push_back(syntheticScene(i));
  EXPECT_EQ(maxDifference(Predictor(model_).predict(scenes), Predictor(options.output).predict(scenes)), 0.0);
  // Issue 29: the same bytes too - the archive's entries never carry a temporary file name.
  EXPECT_EQ(sha256OfFile(options.output), sha256OfFile(model_));
  EXPECT_EQ(readTextFile(options.output).find(".part"), std::string::npos);
  options.seed = 6;
  options.output = dir_.path() / "other.pt";
  train(options);
  EXPECT_GT(maxDifference(Predictor(model_).predict(scenes), Predictor(options.output).predict(scenes)), 1e-3);
}

TEST(ModelTraining, ATinyModelOverfitsAHandfulOfSamples) {
  TemporaryDirectory dir;
  auto options = tinyTraining(writeDataset(dir.path() / "few.h5", 10), dir.path() / "few.pt");
  options.config.hidden = 32;
  options.config.globalWidth = 32;
  options.config.decoderHidden = 64;
  options.validationFraction = 0.1;
  options.steps = 1500;
  options.patience = 100000;  // one validation sample: no early stopping
  options.batchSize = 9;
  options.learningRate = 3e-3;
  const auto summary = train(options);
  // The training ADE of the 9 training samples (the 10th validates) goes to almost zero;
  // the model file holds the best epoch on the held-out sample, not this one.
  EXPECT_GT(summary.epochs.front().trainLoss, 1.0);
  EXPECT_LT(summary.epochs.back().trainLoss, 0.05);
}

TEST(ModelTraining, BadMixesAndDataAreRejected) {
  TemporaryDirectory dir;
  const auto data = writeDataset(dir.path() / "acc.h5", 30);
  auto options = tinyTraining(data, dir.path() / "m.pt");
  auto error_of = [&](const TrainOptions& o) {
    try {
      train(o);
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  options.mix = Mix::parse("acc=0");
  EXPECT_NE(error_of(options).find("the mix is empty"), std::string::npos);
  options.mix = Mix::parse("acc=31");
  EXPECT_NE(error_of(options).find("holds only 30 samples labelled 'acc'"), std::string::npos);
  options.mix = Mix::parse("lk=5");
  EXPECT_NE(error_of(options).find("no sample is labelled 'lk'"), std::string::npos);
  EXPECT_THROW(Mix::parse("acc=2000,acc=3"), ConfigError);
  EXPECT_THROW(Mix::parse("acc:2000"), ConfigError);
  EXPECT_THROW(Mix::parse("acc=-1"), ConfigError);
  options.mix = {};
  options.data = {data, writeDataset(dir.path() / "short.h5", 10, "lk", 10)};
  EXPECT_NE(error_of(options).find("must share step and horizon"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir.path() / "m.pt"));
}

TEST(ModelFiles, CorruptForeignAndOtherSchemaModelsAreRejected) {
  TemporaryDirectory dir;
  const auto garbage = test::writeFile(dir.path() / "garbage.pt", "not a model");
  try {
    Predictor predictor(garbage);
    FAIL();
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("garbage.pt: not a vsd-sumo model file"), std::string::npos);
  }
  EXPECT_THROW(Predictor(dir.path() / "missing.pt"), ModelError);

  // A model for another feature schema (written by a future vsd-sumo).
  const auto data = writeDataset(dir.path() / "acc.h5", 20);
  auto options = tinyTraining(data, dir.path() / "m.pt");
  options.steps = 5;
  train(options);
  const auto bumped = dir.path() / "v2.pt";
  ASSERT_TRUE(test::writeModelForFeatureSchemaV2(options.output, bumped));
  try {
    Predictor predictor(bumped);
    FAIL() << "a model for feature schema v2 was accepted";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("feature schema v2"), std::string::npos) << error.what();
  }
  // A dataset with another horizon than the model's.
  const Predictor predictor(options.output);
  vector::DatasetHeader other;
  other.step = 0.2;
  other.horizon = 10;
  EXPECT_THROW(predictor.checkCompatible(other, "other.h5"), ModelError);
}

TEST(ModelTraining, InterruptedTrainingKeepsTheBestModelAndResumes) {
  TemporaryDirectory dir;
  const auto data = writeDataset(dir.path() / "acc.h5", 40);
  auto options = tinyTraining(data, dir.path() / "m.pt");
  options.steps = 50;  // 36 training samples / batch 8 = 5 steps per epoch -> 10 epochs
  installInterruptHandlers();
  int epochs_seen = 0;
  EXPECT_THROW(train(options,
                     [&](const EpochRecord&) {
                       if (++epochs_seen == 3) std::raise(SIGINT);
                     }),
               InterruptedError);
  clearInterruption();
  ASSERT_TRUE(fs::exists(options.output));  // the best of the first epochs, complete
  const Predictor interrupted(options.output);
  EXPECT_LE(interrupted.info().epoch, 3);
  options.resume = true;
  const auto summary = train(options);
  EXPECT_EQ(summary.epochs.size(), 10u);  // 3 before + 7 after the interruption
  EXPECT_EQ(summary.epochs.front().epoch, 1);
  EXPECT_EQ(summary.epochs.back().epoch, 10);
  const Predictor resumed(options.output);
  EXPECT_GE(resumed.info().epoch, interrupted.info().epoch);

  auto fresh = tinyTraining(data, dir.path() / "fresh.pt");
  fresh.resume = true;
  EXPECT_THROW(train(fresh), ConfigError);  // nothing to resume
}

// A model file whose description does not match its tensors (edited by hand, or
// written by something else) is refused in one ModelError naming the file and the
// field: never an "internal error" from inside libtorch, never a huge allocation.
TEST_F(ModelTest, DescriptionsThatDoNotMatchTheTensorsAreOneModelError) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"d['config']['hidden'] = 32", "the described architecture (hidden 32"},
      {"d['config']['decoder_hidden'] = 8", "needs"},
      {"d['config']['subgraph_layers'] = 2", "has no place in the described architecture (hidden 16, subgraph_layers 2"},
      {"d['config']['hidden'] = 1e300", "hidden: got 1e+300, expected a whole number"},
      {"d['config']['global_width'] = 64.5", "global_width: got 64.5, expected a whole number"},
      {"d['config']['horizon'] = 100000", "horizon: got '100000', expected 1 .. 1000 steps"},
      {"d['config']['heads'] = 3", "heads: got '3', expected a divisor of global_width"},
      {"d['config']['step'] = -0.2", "step: got '-0.2'"},
      {"d['config']['hidden'] = '16'", "hidden: got \"16\", expected a whole number"},
      {"del d['config']['horizon']", "damaged model description"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto& [edit, expected] = cases[i];
    const auto copy = dir_.path() / fmt::format("edited{}.pt", i);
    ASSERT_TRUE(test::rewriteModelDescription(model_, copy, edit)) << edit;
    try {
      const Predictor predictor(copy);
      predictor.predict({syntheticScene(0, "acc")});
      ADD_FAILURE() << edit << ": accepted";
    } catch (const ModelError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(expected), std::string::npos) << edit << ": " << message;
      EXPECT_EQ(message.rfind(copy.string(), 0), 0u) << edit << ": " << message;
    }
  }
}

// --resume repeats an interrupted training exactly, so it must be the same training:
// other data or other settings are refused, naming what differs.
TEST(ModelTraining, ResumeWithOtherDataOrSettingsIsRefused) {
  TemporaryDirectory dir;
  const auto data = writeDataset(dir.path() / "acc.h5", 20);
  auto options = tinyTraining(data, dir.path() / "m.pt");
  options.steps = 10;
  // Interrupted after its second epoch: <out>.last holds its state (a finished one leaves none).
  installInterruptHandlers();
  int epochs = 0;
  EXPECT_THROW(train(options, [&](const EpochRecord&) {
                 if (++epochs == 2) std::raise(SIGINT);
               }),
               InterruptedError);
  clearInterruption();
  options.resume = true;
  const auto refused = [&](TrainOptions changed, const std::string& expected) {
    try {
      train(changed);
      ADD_FAILURE() << "resumed although " << expected;
    } catch (const ConfigError& error) {
      EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
    }
  };
  auto other_data = options;
  other_data.data = {writeDataset(dir.path() / "other.h5", 21)};
  refused(other_data, "was trained on other data");
  auto other_batch = options;
  other_batch.batchSize = 4;
  refused(other_batch, "was trained with batch 8, this training has 4");
  auto other_width = options;
  other_width.config.hidden = 8;
  refused(other_width, "architecture");
  const std::string best = readTextFile(options.output);
  fs::remove(options.output);  // the best model of the interrupted training is gone
  refused(options, "is gone");
  writeTextFileAtomically(options.output, best);
  EXPECT_NO_THROW(train(options));  // the same training resumes and finishes
  EXPECT_FALSE(fs::exists(options.output.string() + ".last")) << "a finished training leaves no resume state";
}

TEST_F(ModelTest, FineTuningStartsFromTheGivenModel) {
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 10; ++i) scenes.push_back(syntheticScene(i));
  // One step at a negligible learning rate: a fine-tuned model predicts what its start does,
  // a fresh one (same seed and settings) does not.
  auto tuned = tinyTraining(data_, dir_.path() / "tuned.pt");
  tuned.initialModel = model_;
  tuned.steps = 1;
  tuned.learningRate = 1e-12;
  train(tuned);
  EXPECT_LT(maxDifference(Predictor(model_).predict(scenes), Predictor(tuned.output).predict(scenes)), 1e-4);
  auto fresh = tuned;
  fresh.initialModel.clear();
  fresh.output = dir_.path() / "fresh.pt";
  train(fresh);
  EXPECT_GT(maxDifference(Predictor(model_).predict(scenes), Predictor(fresh.output).predict(scenes)), 1e-2);
  // At the usual learning rate, fine-tuning's first epoch starts from what the model learnt
  // (training loss 1.79 against a fresh model's 2.19 here).
  tuned.learningRate = fresh.learningRate = tinyTraining(data_, model_).learningRate;
  tuned.steps = fresh.steps = 5;
  const double tuned_loss = train(tuned).epochs.front().trainLoss;
  const double fresh_loss = train(fresh).epochs.front().trainLoss;
  EXPECT_LT(tuned_loss, 0.9 * fresh_loss);
}

TEST_F(ModelTest, FineTuningAnotherArchitectureOrAMissingFileIsRefused) {
  auto options = tinyTraining(data_, dir_.path() / "tuned.pt");
  options.initialModel = model_;
  options.config.hidden = 8;
  try {
    train(options);
    ADD_FAILURE() << "fine-tuned a model of another width";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("--init-from: " + model_.string() + " has hidden 16, this training 8"),
              std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(options.output));
  options.config.hidden = 16;
  options.initialModel = dir_.path() / "missing.pt";
  try {
    train(options);
    ADD_FAILURE() << "fine-tuned a missing model";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("--init-from"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("missing.pt"), std::string::npos) << error.what();
  }
}
