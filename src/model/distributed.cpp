#define USE_C10D_GLOO 1  // ProcessGroupGloo.hpp declares its class only under this (as libtorch is built)

#include "distributed.hpp"

#include <fmt/format.h>
#include <glog/logging.h>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include <charconv>
#include <cstdlib>
#include <functional>
#include <thread>

#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"

namespace vsd::model {

namespace {

const char* environment(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : nullptr;
}

/// An integer environment variable in [low, high]; throws ConfigError naming it.
int integerVariable(const char* name, const char* value, int low, int high) {
  int result = 0;
  const std::string text(value);
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), result);
  if (error != std::errc() || end != text.data() + text.size() || result < low || result > high) {
    throw ConfigError(fmt::format("environment variable {}: got '{}', expected an integer in [{}, {}]", name, text,
                                  low, high));
  }
  return result;
}

std::chrono::seconds secondsVariable(const char* name, int fallback) {
  const char* value = environment(name);
  return std::chrono::seconds(value == nullptr ? fallback : integerVariable(name, value, 1, 86400 * 7));
}

/// The first line of a libtorch error (its backtrace and source location follow).
std::string firstLine(const std::exception& error) {
  const auto* c10_error = dynamic_cast<const c10::Error*>(&error);
  std::string text = c10_error != nullptr ? c10_error->what_without_backtrace() : error.what();
  const auto end = text.find('\n');
  return end == std::string::npos ? text : text.substr(0, end);
}

std::vector<std::uint8_t> bytes(const std::string& text) { return {text.begin(), text.end()}; }
std::string text(const std::vector<std::uint8_t>& bytes) { return {bytes.begin(), bytes.end()}; }

}  // namespace

std::optional<Rendezvous> rendezvousFromEnvironment() {
  Rendezvous r;
  const char* size_name = "WORLD_SIZE";
  const char* rank_name = "RANK";
  if (environment(size_name) == nullptr && environment("OMPI_COMM_WORLD_SIZE") != nullptr) {
    size_name = "OMPI_COMM_WORLD_SIZE";
    rank_name = "OMPI_COMM_WORLD_RANK";
  }
  const char* size = environment(size_name);
  if (size == nullptr) return std::nullopt;
  r.size = integerVariable(size_name, size, 1, 1 << 20);
  if (r.size == 1) return std::nullopt;
  const char* rank = environment(rank_name);
  if (rank == nullptr) {
    throw ConfigError(fmt::format("environment variable {} is {} but {} is not set: each process of a distributed "
                                  "training needs its rank",
                                  size_name, r.size, rank_name));
  }
  r.rank = integerVariable(rank_name, rank, 0, r.size - 1);
  r.source = fmt::format("{}/{}", size_name, rank_name);
  if (const char* address = environment("MASTER_ADDR")) {
    r.address = address;
  } else {
    // mpirun on one node: every rank reaches rank 0 on the loopback interface.
    const char* local_size = environment("OMPI_COMM_WORLD_LOCAL_SIZE");
    if (std::string(size_name) != "OMPI_COMM_WORLD_SIZE" || local_size == nullptr || std::string(local_size) != size) {
      throw ConfigError(fmt::format("environment variable MASTER_ADDR is not set: a distributed training over "
                                    "{} ranks ({}={}) needs the address of rank 0's host",
                                    r.size, size_name, r.size));
    }
    r.address = "127.0.0.1";
  }
  if (const char* port = environment("MASTER_PORT")) r.port = integerVariable("MASTER_PORT", port, 1, 65535);
  r.timeout = secondsVariable("VSD_RENDEZVOUS_TIMEOUT", 120);
  r.collectiveTimeout = secondsVariable("VSD_COLLECTIVE_TIMEOUT", 1800);
  return r;
}

struct DataParallel::Group {
  c10::intrusive_ptr<c10d::TCPStore> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> gloo;
};

namespace {

/// Where this process waits and what it says when the wait times out.
std::string where(const Rendezvous& r) {
  return fmt::format("the training rendezvous at MASTER_ADDR={} MASTER_PORT={} (rank {} of {}, {})", r.address,
                     r.port, r.rank, r.size, r.source);
}

c10::intrusive_ptr<c10d::TCPStore> connectStore(const Rendezvous& r) {
  c10d::TCPStoreOptions options;
  options.port = static_cast<std::uint16_t>(r.port);
  options.isServer = r.rank == 0;
  options.numWorkers = static_cast<std::size_t>(r.size);
  options.waitWorkers = false;  // the handshake below waits, with a message that names who is missing
  options.timeout = r.timeout;
  try {
    return c10::make_intrusive<c10d::TCPStore>(r.address, options);
  } catch (const std::exception& error) {
    throw ConfigError(fmt::format("cannot {} {} within {} s: {}", r.rank == 0 ? "open" : "reach", where(r),
                                  r.timeout.count(), firstLine(error)));
  }
}

std::string sizeMismatch(const Rendezvous& r, const std::string& rank0_size, int other, const std::string& other_size) {
  return fmt::format("world size mismatch: rank 0 was started with a world of {} ranks, rank {} with {} (every rank "
                     "needs the same {})",
                     rank0_size, other, other_size, r.source.substr(0, r.source.find('/')));
}

/// Every rank announces its world size; rank 0 checks them and says "go" (or why not)
/// to all, so that no rank waits in the process group for a rank that gave up.
void handshake(c10d::TCPStore& store, const Rendezvous& r) {
  if (store.add(fmt::format("vsd/rank/{}", r.rank), 1) > 1) {
    throw ConfigError(fmt::format("{}: another process already joined as rank {}", where(r), r.rank));
  }
  store.set(fmt::format("vsd/size/{}", r.rank), bytes(std::to_string(r.size)));
  if (r.rank != 0) {
    store.wait({"vsd/size/0"}, r.timeout);
    const auto rank0_size = text(store.get("vsd/size/0"));
    if (rank0_size != std::to_string(r.size)) throw ConfigError(sizeMismatch(r, rank0_size, r.rank, std::to_string(r.size)));
    store.wait({"vsd/go"}, r.timeout);
    const auto verdict = text(store.get("vsd/go"));
    store.add("vsd/read", 1);
    if (verdict != "go") throw ConfigError(verdict);
    return;
  }
  std::vector<std::string> missing;
  std::string verdict = "go";
  for (int other = 1; other < r.size; ++other) {
    const auto key = fmt::format("vsd/size/{}", other);
    try {
      store.wait({key}, r.timeout);
    } catch (const std::exception&) {
      missing.push_back(std::to_string(other));
      continue;
    }
    const auto size = text(store.get(key));
    if (size != std::to_string(r.size) && verdict == "go") verdict = sizeMismatch(r, std::to_string(r.size), other, size);
  }
  if (!missing.empty() && verdict == "go") {
    verdict = fmt::format("{}: rank(s) {} did not join within {} s", where(r), fmt::join(missing, ", "),
                          r.timeout.count());
  }
  store.set("vsd/go", bytes(verdict));
  if (verdict != "go") {
    // This process serves the store: stay until the ranks that joined have read why (at most 5 s).
    const auto joined = static_cast<std::int64_t>(r.size - 1 - static_cast<int>(missing.size()));
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (store.add("vsd/read", 0) < joined && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw ConfigError(verdict);
  }
}

std::shared_ptr<::gloo::transport::Device> glooDevice(const Rendezvous& r) {
  if (const char* interface = environment("GLOO_SOCKET_IFNAME")) {
    return c10d::ProcessGroupGloo::createDeviceForInterface(interface);
  }
  const bool loopback = r.address == "localhost" || r.address.rfind("127.", 0) == 0;
  return loopback ? c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1")
                  : c10d::ProcessGroupGloo::createDefaultDevice();
}

}  // namespace

DataParallel::DataParallel(const Rendezvous& rendezvous) : rendezvous_(rendezvous), group_(std::make_unique<Group>()) {
  // c10d logs every connection retry and timeout through glog; the errors thrown here say it
  // in one line (GLOG_minloglevel, when set, still decides).
  if (environment("GLOG_minloglevel") == nullptr) FLAGS_minloglevel = google::GLOG_FATAL;
  group_->store = connectStore(rendezvous_);
  try {
    handshake(*group_->store, rendezvous_);
    auto options = c10d::ProcessGroupGloo::Options::create(rendezvous_.collectiveTimeout);
    options->devices = {glooDevice(rendezvous_)};
    options->threads = 1;
    group_->gloo = c10::make_intrusive<c10d::ProcessGroupGloo>(group_->store, rendezvous_.rank, rendezvous_.size,
                                                               options);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& error) {
    throw ConfigError(fmt::format("{}: {}", where(rendezvous_), firstLine(error)));
  }
}

DataParallel::~DataParallel() = default;

std::pair<std::int64_t, std::int64_t> DataParallel::slice(std::int64_t n) const {
  return {n * rank() / size(), n * (rank() + 1) / size()};
}

void DataParallel::collective(const char* what, const std::function<void()>& operation) {
  const auto start = std::chrono::steady_clock::now();
  try {
    operation();
  } catch (const std::exception& error) {
    throw ModelError(fmt::format("distributed training, rank {} of {}: the {} with the other ranks failed (a rank "
                                 "ended or the network failed): {}",
                                 rank(), size(), what, firstLine(error)));
  }
  communicationSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void DataParallel::sum(torch::Tensor& values) {
  collective("all-reduce", [&] {
    std::vector<torch::Tensor> tensors{values};
    group_->gloo->allreduce(tensors)->wait();
  });
}

void DataParallel::max(torch::Tensor& values) {
  collective("all-reduce", [&] {
    std::vector<torch::Tensor> tensors{values};
    c10d::AllreduceOptions options;
    options.reduceOp = c10d::ReduceOp::MAX;
    group_->gloo->allreduce(tensors, options)->wait();
  });
}

void DataParallel::broadcastFromRankZero(torch::Tensor& values) {
  collective("broadcast", [&] {
    std::vector<torch::Tensor> tensors{values};
    group_->gloo->broadcast(tensors)->wait();
  });
}

void DataParallel::requireSameOnEveryRank(const std::string& fingerprint, const std::string& what) {
  // Two halves of the hash and their negations: max == -max(-x) on every rank iff all agree.
  const auto hash = static_cast<std::uint64_t>(std::hash<std::string>{}(fingerprint));
  const auto low = static_cast<std::int64_t>(hash & 0xffffffffu);
  const auto high = static_cast<std::int64_t>(hash >> 32);
  auto values = torch::tensor({low, high, -low, -high}, torch::kInt64);
  max(values);
  const auto v = values.accessor<std::int64_t, 1>();
  if (v[0] != -v[2] || v[1] != -v[3]) {
    throw ConfigError(fmt::format("distributed training, rank {} of {}: the ranks differ in {} (start every rank "
                                  "with the same options and data)",
                                  rank(), size(), what));
  }
}

GlobalStep globalStep(DataParallel& parallel, Model& model, const SceneTensors& slice, double weight) {
  const auto parameters = model.network->parameters();
  double loss = 0.0;
  double variance_not_finite = 0.0;
  if (slice.size() > 0) {
    const auto decoded = model.decode(slice);
    const auto batch_loss = model.decoder->loss(decoded, slice.targets, slice.targetMask);
    loss = batch_loss.item<double>();
    if (decoded.covariance.defined() && !decoded.covariance.isfinite().all().item<bool>()) variance_not_finite = 1.0;
    (batch_loss * weight).backward();
  }
  // One flat buffer: the weighted gradients, then the weighted loss and the two flags.
  std::vector<torch::Tensor> parts;
  parts.reserve(parameters.size() + 1);
  for (const auto& p : parameters) {
    parts.push_back(p.grad().defined() ? p.grad().reshape({-1}) : torch::zeros({p.numel()}, p.options()));
  }
  parts.push_back(torch::tensor({static_cast<float>(loss * weight), static_cast<float>(variance_not_finite),
                                 interrupted() ? 1.0f : 0.0f}));
  auto flat = torch::cat(parts);
  parallel.sum(flat);
  std::int64_t offset = 0;
  {
    torch::NoGradGuard no_grad;
    for (auto& p : model.network->parameters()) {
      const auto part = flat.narrow(0, offset, p.numel()).view_as(p);
      if (p.grad().defined()) {
        p.mutable_grad().copy_(part);
      } else {
        p.mutable_grad() = part.clone();
      }
      offset += p.numel();
    }
  }
  const auto tail = flat.narrow(0, offset, 3);
  GlobalStep step;
  step.loss = tail[0].item<double>();
  step.varianceFinite = tail[1].item<double>() == 0.0;
  step.interrupted = tail[2].item<double>() > 0.0;
  return step;
}

}  // namespace vsd::model
