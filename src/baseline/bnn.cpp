// Bayesian neural network by Bayes by Backprop (libtorch stays inside this file).
#include <torch/torch.h>

#include <fmt/format.h>

#include <cmath>

#include "vsd/baseline/baseline.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/random.hpp"
#include "vsd/core/threads.hpp"

namespace vsd::baseline {

void BnnOptions::validate() const {
  auto require = [](bool ok, const char* field, double value, const char* constraint) {
    if (!ok) throw ConfigError::field("bnn", field, fmt::format("{}", value), constraint);
  };
  require(hidden >= 1 && hidden <= 4096, "hidden", hidden, "1 .. 4096");
  require(layers >= 1 && layers <= 16, "layers", layers, "1 .. 16");
  require(epochs >= 1 && epochs <= 1000000, "epochs", epochs, "1 .. 1000000");
  require(batchSize >= 1 && batchSize <= 65536, "batch", batchSize, "1 .. 65536");
  require(learningRate > 0.0 && learningRate <= 10.0, "lr", learningRate, "(0, 10]");
  require(priorStd > 0.0 && priorStd <= 1e6, "prior_std", priorStd, "(0, 1e6]");
  require(samples >= 1 && samples <= 100000, "samples", samples, "1 .. 100000");
  require(threads >= 1 && threads <= 256, "threads", threads, "1 .. 256");
}

namespace {

/// A linear layer with a Gaussian weight posterior, sampled with the local
/// reparameterisation trick (the pre-activations are sampled, not the weights).
class BayesianLinearImpl : public torch::nn::Module {
 public:
  BayesianLinearImpl(int in, int out, double prior_std) : priorStd_(prior_std) {
    weightMean_ = register_parameter("weight_mean", torch::randn({out, in}) * std::sqrt(1.0 / in));
    weightRho_ = register_parameter("weight_rho", torch::full({out, in}, -5.0));
    biasMean_ = register_parameter("bias_mean", torch::zeros({out}));
    biasRho_ = register_parameter("bias_rho", torch::full({out}, -5.0));
  }

  torch::Tensor forward(const torch::Tensor& x) {
    const auto weight_var = torch::softplus(weightRho_).pow(2);
    const auto bias_var = torch::softplus(biasRho_).pow(2);
    const auto mean = torch::addmm(biasMean_, x, weightMean_.t());
    const auto variance = torch::addmm(bias_var, x.pow(2), weight_var.t());
    return mean + variance.clamp_min(1e-12).sqrt() * torch::randn_like(mean);
  }

  /// KL(q || prior) in closed form, summed over all weights.
  torch::Tensor kl() const {
    auto term = [&](const torch::Tensor& mean, const torch::Tensor& rho) {
      const auto sigma = torch::softplus(rho);
      return (std::log(priorStd_) - sigma.log() + (sigma.pow(2) + mean.pow(2)) / (2.0 * priorStd_ * priorStd_) - 0.5).sum();
    };
    return term(weightMean_, weightRho_) + term(biasMean_, biasRho_);
  }

 private:
  double priorStd_;
  torch::Tensor weightMean_, weightRho_, biasMean_, biasRho_;
};
TORCH_MODULE(BayesianLinear);

class BnnImpl : public torch::nn::Module {
 public:
  BnnImpl(int inputs, int outputs, const BnnOptions& options) {
    int width = inputs;
    for (int l = 0; l < options.layers; ++l) {
      layers_.push_back(register_module(fmt::format("hidden{}", l), BayesianLinear(width, options.hidden, options.priorStd)));
      width = options.hidden;
    }
    output_ = register_module("output", BayesianLinear(width, outputs, options.priorStd));
    logNoise_ = register_parameter("log_noise", torch::full({outputs}, std::log(0.3)));
  }
  torch::Tensor forward(torch::Tensor x) {
    for (auto& layer : layers_) x = torch::relu(layer->forward(x));
    return output_->forward(x);
  }
  torch::Tensor kl() const {
    auto total = output_->kl();
    for (const auto& layer : layers_) total = total + layer->kl();
    return total;
  }
  const torch::Tensor& logNoise() const { return logNoise_; }

 private:
  std::vector<BayesianLinear> layers_;
  BayesianLinear output_{nullptr};
  torch::Tensor logNoise_;
};
TORCH_MODULE(Bnn);

torch::Tensor toTensor(const Matrix& m) {
  torch::Tensor t = torch::empty({m.rows(), m.cols()}, torch::kFloat32);
  auto a = t.accessor<float, 2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) a[r][c] = static_cast<float>(m(r, c));
  }
  return t;
}

}  // namespace

struct BayesianNetwork::Impl {
  BnnOptions options;
  mutable Bnn network{nullptr};  // forward() is not const in libtorch, even without gradients
  Eigen::RowVectorXd inputMean, inputStd, targetMean, targetStd;
};

BayesianNetwork::BayesianNetwork(BnnOptions options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  impl_->options = options;
}
BayesianNetwork::~BayesianNetwork() = default;
BayesianNetwork::BayesianNetwork(BayesianNetwork&&) noexcept = default;
BayesianNetwork& BayesianNetwork::operator=(BayesianNetwork&&) noexcept = default;

void BayesianNetwork::fit(const Matrix& x, const Matrix& y) {
  if (x.rows() < 2 || x.rows() != y.rows() || x.cols() == 0 || y.cols() == 0) {
    throw ConfigError(fmt::format("bnn: cannot fit {} x {} inputs to {} x {} targets", x.rows(), x.cols(), y.rows(),
                                  y.cols()));
  }
  auto& d = *impl_;
  at::set_num_threads(d.options.threads);
  setBlasThreads(1);
  torch::manual_seed(d.options.seed);
  auto standardise = [](const Matrix& m, Eigen::RowVectorXd& mean, Eigen::RowVectorXd& std) {
    mean = m.colwise().mean();
    std = ((m.rowwise() - mean).array().square().colwise().mean()).sqrt().matrix();
    for (Eigen::Index c = 0; c < std.size(); ++c) {
      if (std(c) < 1e-12) std(c) = 1.0;  // constant column
    }
    return Matrix(((m.rowwise() - mean).array().rowwise() / std.array()).matrix());
  };
  const auto xs = toTensor(standardise(x, d.inputMean, d.inputStd));
  const auto ys = toTensor(standardise(y, d.targetMean, d.targetStd));
  d.network = Bnn(static_cast<int>(x.cols()), static_cast<int>(y.cols()), d.options);
  torch::optim::Adam optimizer(d.network->parameters(), torch::optim::AdamOptions(d.options.learningRate));
  const auto n = xs.size(0);
  Rng rng = Rng::derive(d.options.seed, 0, RandomStream::Training);
  for (int epoch = 0; epoch < d.options.epochs; ++epoch) {
    const auto order = rng.permutation(static_cast<std::size_t>(n));
    const auto order_tensor = torch::tensor(std::vector<std::int64_t>(order.begin(), order.end()), torch::kInt64);
    for (std::int64_t first = 0; first < n; first += d.options.batchSize) {
      const auto index = order_tensor.slice(0, first, std::min<std::int64_t>(first + d.options.batchSize, n));
      const auto xb = xs.index_select(0, index);
      const auto yb = ys.index_select(0, index);
      optimizer.zero_grad();
      const auto prediction = d.network->forward(xb);
      const auto log_noise = d.network->logNoise();
      // Gaussian negative log-likelihood per sample, KL spread over the whole dataset.
      const auto nll = (0.5 * ((yb - prediction) / log_noise.exp()).pow(2) + log_noise).sum(1).mean();
      const auto loss = nll + d.network->kl() / static_cast<double>(n);
      loss.backward();
      optimizer.step();
    }
  }
}

BnnPrediction BayesianNetwork::predict(const Matrix& x) const {
  const auto& d = *impl_;
  if (!d.network) throw Error("bnn: predict() before fit()");
  if (x.cols() != d.inputMean.size()) {
    throw ConfigError(fmt::format("bnn: fitted on {} inputs, asked with {}", d.inputMean.size(), x.cols()));
  }
  torch::NoGradGuard no_grad;
  const Matrix standardised = ((x.rowwise() - d.inputMean).array().rowwise() / d.inputStd.array()).matrix();
  const auto xs = toTensor(standardised);
  torch::manual_seed(d.options.seed + 1);  // deterministic predictions
  std::vector<torch::Tensor> draws;
  for (int s = 0; s < d.options.samples; ++s) draws.push_back(d.network->forward(xs));
  const auto stacked = torch::stack(draws);                                   // [S, n, outputs]
  const auto mean = stacked.mean(0);
  const auto noise = d.network->logNoise().exp().pow(2);
  const auto std = (stacked.var(0, /*unbiased=*/false) + noise).sqrt();
  BnnPrediction prediction;
  prediction.mean.resize(x.rows(), d.targetMean.size());
  prediction.std.resize(x.rows(), d.targetMean.size());
  const auto m = mean.accessor<float, 2>();
  const auto s = std.accessor<float, 2>();
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    for (Eigen::Index c = 0; c < d.targetMean.size(); ++c) {
      prediction.mean(r, c) = static_cast<double>(m[r][c]) * d.targetStd(c) + d.targetMean(c);
      prediction.std(r, c) = static_cast<double>(s[r][c]) * d.targetStd(c);
    }
  }
  return prediction;
}

}  // namespace vsd::baseline
