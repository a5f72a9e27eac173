#pragma once
// The processes of one job on a cluster: MPI ranks started by `mpirun`, or one
// process. `run` and `export` split their work by rank; everything else about
// the work is the same code as in a one-process run.
//
// MPI is optional at build time (CMake finds Open MPI or not). A process started
// by mpirun in a build without MPI refuses to run, instead of N copies of the same
// sweep writing the same folder.

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace vsd::pipeline {

/// Communication between the ranks of a job. Rank 0 reports.
class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// Waits until every rank arrived.
  virtual void barrier() = 0;
  /// Every rank receives every rank's `text`, in rank order.
  virtual std::vector<std::string> allGather(const std::string& text) = 0;
  /// Ends every rank of the job with `exit_code` (after this rank failed).
  [[noreturn]] virtual void abort(int exit_code) = 0;
};

/// True if mpirun (Open MPI, or a PMI/PMIx launcher such as srun) started this process.
bool launchedAsMpiRank();

/// "Open MPI 4.1.4 ..." if this build has MPI, else an empty string.
std::string mpiLibraryVersion();

/// Joins the MPI job (MPI_Init; MPI_Finalize when the returned object is destroyed).
/// Throws ConfigError if this build has no MPI.
std::unique_ptr<Communicator> joinMpiJob();

/// Runs `checks` (option and input checks that every rank makes alike) on every rank
/// and agrees on the outcome: if any rank's checks throw ConfigError, rank 0 prints
/// one error line, every rank waits until it has, and all return false (exit code 1;
/// no rank dies before rank 0 reported, so mpirun cannot cut the message off).
bool checkOnEveryRank(Communicator& communicator, const std::function<void()>& checks);

/// Runs this rank's share of the work; if it throws, prints one line naming the rank
/// and what failed and ends the whole job (MPI_Abort), so no rank waits for a dead one.
void workOrEndJob(Communicator& communicator, const std::string& what, const std::function<void()>& work);

}  // namespace vsd::pipeline

namespace vsd::pipeline {

struct RunOptions;

/// What `mpirun -n N vsd-sumo run` ends with on this rank.
struct ClusterRunResult {
  int exitCode = 0;
  std::string report;  ///< rank 0: the job's summary; other ranks: empty
};

/// `run` on an MPI job: rank r runs shard r of N of the sweep (RunOptions::shard),
/// writing only its own shard folder, so no rank's I/O waits for another's; shards
/// finished by an earlier attempt are not run again (a re-run resumes). Rank 0
/// gathers the shard summaries; with `merge`, it then joins the shards (merge.hpp).
/// Faults every rank detects alike (bad options, more ranks than batches) are
/// reported by rank 0 alone and end every rank with exit code 1; a fault of one rank
/// is reported with its rank and ends the whole job (MPI_Abort), so no rank waits
/// for a dead one.
ClusterRunResult runOnCluster(const RunOptions& options, bool merge, Communicator& communicator);

}  // namespace vsd::pipeline
