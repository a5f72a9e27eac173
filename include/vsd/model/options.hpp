#pragma once
// What a model is (architecture, decoder, representation) and how it is trained.
// Free of libtorch so that every module can include it.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace vsd::model {

struct MetricBinding;  // predictor.hpp

/// One option of a decoder: numbers only (flags are 0/1), stored in the model file.
struct DecoderOption {
  std::string name;
  double defaultValue = 0.0;
  double min = 0.0;  ///< inclusive
  double max = 0.0;  ///< inclusive
  std::string meaning;  ///< one line, with the unit
};

/// A decoder as the registry describes it (README "Decoders").
struct DecoderInfo {
  std::string name;
  std::string description;
  bool probabilistic = false;  ///< predicts a distribution (samples, covariance, NLL)
  bool kinematic = false;      ///< predicts speeds and accelerations (not only positions)
  std::vector<DecoderOption> options;
  /// Options added after model format 2 (vsd-model/2 files lack them), each with the value
  /// that reproduces how such a file's decoder behaved. Loading one fills them in.
  std::map<std::string, double> optionsBeforeModelFormat3;
};

struct DecoderEntry;  // src/model/decoder.hpp: a DecoderInfo and the factory of its decoder

/// The decoders a model configuration can name, one entry each: what the decoder is
/// (DecoderInfo) and how to build it. A registry is an object handed to its users, never a
/// process-wide list: the built-ins come from withBuiltins(); a test or a tool with a decoder
/// of its own adds it to its own registry and hands that on (VectorNetConfig::decoders for
/// training, the Predictor's constructor for loading its model files).
/// Public, so that every module can validate a configuration; the entries are opaque here
/// because their factories build libtorch modules (the type is internal to the model module),
/// and shared, so that copies of a registry are cheap.
class DecoderRegistry {
 public:
  /// The built-in decoders (the one list: src/model/decoder_registry.cpp).
  static DecoderRegistry withBuiltins();
  /// Adds a decoder written outside the model module's list (its own file and this one call).
  /// Throws ConfigError for a name that is taken or an entry without a name or a factory.
  void add(DecoderEntry entry);
  /// Every decoder's description, in registry order.
  std::vector<DecoderInfo> available() const;
  bool contains(const std::string& name) const;
  /// The decoder called `name`. Throws ConfigError naming `where` and listing the known decoders.
  const DecoderInfo& find(const std::string& name, const std::string& where) const;
  /// The entry of `name` (internal: needs src/model/decoder.hpp). Throws as find().
  const DecoderEntry& entry(const std::string& name, const std::string& where) const;

 private:
  std::vector<std::shared_ptr<const DecoderEntry>> entries_;
};

/// The built-in decoders (DecoderRegistry::withBuiltins()), built once and never changed:
/// what a configuration and a model file's loader use unless they are handed another registry.
std::shared_ptr<const DecoderRegistry> builtinDecoders();

/// Names of the coordinate frames a model can work in (README "Representations"):
/// "ego"  - translated to the Ego's initial position and rotated by its heading (the paper's);
/// "lane" - a lane-relative (Frenet) frame along the lane the Ego starts on.
const std::vector<std::string>& availableFrames();

/// Architecture hyper-parameters, the decoder and the representation (stored in the model file).
struct VectorNetConfig {
  int hidden = 64;           ///< width of the subgraph layers and of polyline features
  int subgraphLayers = 3;
  int globalWidth = 128;     ///< width of the attention's queries, keys and values
  int heads = 1;             ///< attention heads (globalWidth must be divisible by heads)
  int decoderHidden = 256;
  /// Predicted steps and the time between them: no default - they come from the training
  /// data's header (or the model file) and are passed on.
  int horizon = 0;
  double step = 0.0;         ///< s
  double coordinateScale = 10.0;  ///< m: model-frame coordinates are divided by this before the network
  std::string decoder = "offsets";             ///< a name of `decoders`
  std::map<std::string, double> decoderOptions;  ///< given options; the rest take the decoder's defaults
  std::string frame = "ego";                     ///< a name of availableFrames()
  /// m, in (0, 20]: half-width of the moving average that smooths the lane frame's reference
  /// line (lane frame only). Measured on row 8 (README "Lane frame smoothing"): 2 / 3 / 4 m
  /// leave the maximum lane offset of predictions at -0.05 / +-0.02 / +0.13 m bias; model files
  /// before vsd-model/4 used 4 m.
  double laneSmoothing = 3.0;
  /// Where `decoder` is looked up (its options, defaults and factory). Not part of what the
  /// model is - a model file stores the decoder's name - but carried with the configuration
  /// because everything that reads a configuration (validation, option defaults, building the
  /// model, training, calibration) needs it: one field instead of a parameter on each.
  std::shared_ptr<const DecoderRegistry> decoders = builtinDecoders();

  /// *decoders; throws ConfigError if it is empty.
  const DecoderRegistry& decoderRegistry() const;
  /// The value of a decoder option: the given one or the decoder's default.
  /// Throws ConfigError for an option the decoder does not have.
  double decoderOption(const std::string& name) const;
  /// Throws ConfigError naming the field and the constraint (unknown decoder or option,
  /// option out of range, unknown frame, ...). `horizon`/`step` are checked only when set.
  void validate() const;
};

/// "name=value" pairs of --decoder-option into a map; values are numbers or true/false/on/off.
/// Throws ConfigError naming the flag and the text.
std::map<std::string, double> parseDecoderOptions(const std::vector<std::string>& items);

/// How many samples of each label to train on, e.g. "acc=2000,lk=2000,acc_lk=200".
struct Mix {
  std::vector<std::pair<std::string, std::size_t>> counts;
  /// Throws ConfigError for malformed text, counts < 0 or a label named twice; "" is empty.
  static Mix parse(const std::string& text);
  std::size_t total() const;
  std::string str() const;
};

struct TrainOptions {
  std::vector<std::filesystem::path> data;  ///< dataset files or run folders
  Mix mix;                                  ///< empty: every sample of every file
  std::filesystem::path output;             ///< model file (.pt); the best epoch by validation ADE
  VectorNetConfig config;                   ///< architecture, decoder (+ options) and frame
  std::uint64_t seed = 1;
  int threads = 2;                          ///< libtorch intra-op threads
  int steps = 6000;                         ///< optimizer steps: the learning-rate schedule's length
  int patience = 40;                        ///< epochs without a better validation ADE before stopping
  int batchSize = 64;
  double learningRate = 2e-3;               ///< peak (after a 200-step warm-up; cosine decay to 2 % by `steps`)
  double weightDecay = 1e-4;
  double validationFraction = 0.1;          ///< the paper's 90 % / 10 % split
  bool resume = false;                      ///< continue from <output>.last if it exists
  /// Fine-tuning: start from this model file's weights instead of fresh ones from `seed`
  /// (the optimizer and the schedule start afresh). Its configuration - architecture,
  /// decoder and options, frame, step, horizon - must equal this training's. Empty: fresh.
  std::filesystem::path initialModel;
  /// The metrics whose intervals the decoder option `calibrate` calibrates on the validation
  /// split (their values on the recorded futures are the references); none when not set.
  std::shared_ptr<const MetricBinding> metrics;
  /// Throws ConfigError naming the flag and the constraint.
  void validate() const;
};

}  // namespace vsd::model
