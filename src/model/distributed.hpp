#pragma once
// Data-parallel training over several processes (c10d ProcessGroupGloo over a TCPStore
// rendezvous). Off unless the environment names more than one rank: WORLD_SIZE / RANK /
// MASTER_ADDR / MASTER_PORT as torchrun sets them, or mpirun's OMPI_COMM_WORLD_SIZE /
// OMPI_COMM_WORLD_RANK (MASTER_ADDR then defaults to 127.0.0.1 when every rank runs on
// this node). Every rank reads the same data and draws the same epoch order; rank r
// trains its contiguous slice of every global batch and the gradients are summed with
// weights (slice size / batch size), which is the gradient of the whole batch's mean
// loss. Rank 0 validates, writes the model file and the resume checkpoint.
//
// Timeouts: VSD_RENDEZVOUS_TIMEOUT (s, default 120) bounds the rendezvous (an unreachable
// MASTER_ADDR, a rank that never starts); VSD_COLLECTIVE_TIMEOUT (s, default 1800) bounds
// one collective (a rank that hangs; a rank that dies closes its sockets and fails the
// others' next collective at once).

#include <torch/torch.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "network.hpp"
#include "tensors.hpp"

namespace vsd::model {

/// Where and as which rank this process joins a distributed training.
struct Rendezvous {
  std::string address;  ///< MASTER_ADDR
  int port = 29500;     ///< MASTER_PORT
  int rank = 0;
  int size = 1;
  std::chrono::seconds timeout{120};
  std::chrono::seconds collectiveTimeout{1800};
  std::string source;  ///< "WORLD_SIZE/RANK" or "OMPI_COMM_WORLD_SIZE/OMPI_COMM_WORLD_RANK"
};

/// The rendezvous the environment describes; nullopt when it names no world or a world of
/// one rank. Throws ConfigError naming the variable for a malformed or inconsistent value.
std::optional<Rendezvous> rendezvousFromEnvironment();

class DataParallel {
 public:
  /// Connects to the other ranks and checks that they agree on the world size and that
  /// no rank number is taken twice. Throws ConfigError with one line (the address, the
  /// rank, what was expected) when the rendezvous times out or the ranks disagree.
  explicit DataParallel(const Rendezvous& rendezvous);
  ~DataParallel();
  DataParallel(const DataParallel&) = delete;
  DataParallel& operator=(const DataParallel&) = delete;

  int rank() const { return rendezvous_.rank; }
  int size() const { return rendezvous_.size; }

  /// This rank's contiguous part [first, last) of the global batch [0, n).
  std::pair<std::int64_t, std::int64_t> slice(std::int64_t n) const;

  /// Sums `values` (a contiguous float or integer tensor) over all ranks in place.
  /// Throws ModelError when a rank died or the collective timed out.
  void sum(torch::Tensor& values);
  /// Element-wise maximum over all ranks, in place.
  void max(torch::Tensor& values);
  /// Replaces `values` by rank 0's.
  void broadcastFromRankZero(torch::Tensor& values);

  /// Throws ConfigError naming `what` unless every rank passes the same `fingerprint`
  /// (the training's options and data, so that ranks cannot silently train different things).
  void requireSameOnEveryRank(const std::string& fingerprint, const std::string& what);

  /// Wall time spent in collectives (waiting for the slowest rank included), s.
  double communicationSeconds() const { return communicationSeconds_; }

 private:
  struct Group;
  void collective(const char* what, const std::function<void()>& operation);

  Rendezvous rendezvous_;
  std::unique_ptr<Group> group_;
  double communicationSeconds_ = 0.0;
};

/// One optimizer step's loss and gradients over all ranks: this rank's `slice` of the
/// global batch (weight = its share of the batch) is forwarded and back-propagated, then
/// the weighted gradients, losses and the flags are summed. Leaves the global batch's
/// gradient in every parameter's .grad on every rank.
struct GlobalStep {
  double loss = 0.0;            ///< the global batch's mean loss
  bool varianceFinite = true;   ///< no rank predicted a non-finite variance
  bool interrupted = false;     ///< some rank received SIGINT/SIGTERM (all stop at this step)
};
GlobalStep globalStep(DataParallel& parallel, Model& model, const SceneTensors& slice, double weight);

}  // namespace vsd::model
