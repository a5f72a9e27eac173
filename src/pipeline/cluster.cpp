#include "vsd/pipeline/cluster.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cstdio>
#include <cstdlib>

#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"

#ifdef VSD_HAVE_MPI
// The C API only: Open MPI's and MPICH's deprecated C++ bindings need extra libraries.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace vsd::pipeline {

bool launchedAsMpiRank() {
  // Open MPI's mpirun, and PMI / PMIx launchers (Slurm's srun, MPICH's hydra).
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"}) {
    if (std::getenv(variable) != nullptr) return true;
  }
  return false;
}

#ifdef VSD_HAVE_MPI

namespace {

class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiCommunicator() override {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  /// Waits without spinning: Open MPI's blocking collectives poll at full speed, which
  /// would take a core from the ranks still working.
  void barrier() override {
    MPI_Request request;
    MPI_Ibarrier(MPI_COMM_WORLD, &request);
    int done = 0;
    while (true) {
      MPI_Test(&request, &done, MPI_STATUS_IGNORE);
      if (done) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  std::vector<std::string> allGather(const std::string& text) override {
    barrier();  // everyone has arrived: the exchange itself is short
    const int length = static_cast<int>(text.size());
    std::vector<int> lengths(static_cast<std::size_t>(size_));
    MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::vector<int> offsets(lengths.size(), 0);
    int total = 0;
    for (std::size_t r = 0; r < lengths.size(); ++r) {
      offsets[r] = total;
      total += lengths[r];
    }
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Allgatherv(text.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR,
                   MPI_COMM_WORLD);
    std::vector<std::string> texts;
    for (std::size_t r = 0; r < lengths.size(); ++r) {
      texts.push_back(all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(lengths[r])));
    }
    return texts;
  }

  [[noreturn]] void abort(int exit_code) override {
    MPI_Abort(MPI_COMM_WORLD, exit_code);
    std::_Exit(exit_code);  // MPI_Abort does not return; this keeps [[noreturn]] honest
  }

 private:
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace

std::string mpiLibraryVersion() {
  char version[MPI_MAX_LIBRARY_VERSION_STRING];
  int length = 0;
  MPI_Get_library_version(version, &length);
  std::string text(version, static_cast<std::size_t>(length));
  const auto comma = text.find(',');  // "Open MPI v4.1.4, package: ..." -> "Open MPI v4.1.4"
  return comma == std::string::npos ? text : text.substr(0, comma);
}

std::unique_ptr<Communicator> joinMpiJob() { return std::make_unique<MpiCommunicator>(); }

#else

std::string mpiLibraryVersion() { return {}; }

std::unique_ptr<Communicator> joinMpiJob() {
  throw ConfigError(
      "this process was started by mpirun, but this vsd-sumo was built without MPI (install libopenmpi-dev and "
      "rebuild): without it every rank would run the whole job");
}

#endif

bool checkOnEveryRank(Communicator& communicator, const std::function<void()>& checks) {
  std::string failure;
  try {
    checks();
  } catch (const ConfigError& error) {
    failure = error.what();
    if (failure.empty()) failure = "invalid configuration";
  }
  const auto failures = communicator.allGather(failure);
  const auto first = std::find_if(failures.begin(), failures.end(), [](const std::string& f) { return !f.empty(); });
  if (first == failures.end()) return true;
  if (communicator.rank() == 0) {
    const bool everywhere = std::all_of(failures.begin(), failures.end(), [&](const std::string& f) { return f == *first; });
    const std::string where =
        everywhere ? "" : fmt::format("rank {} of {}: ", std::distance(failures.begin(), first), communicator.size());
    std::fprintf(stderr, "vsd-sumo: error: %s%s\n", where.c_str(), first->c_str());
    std::fflush(stderr);
  }
  communicator.barrier();
  return false;
}

void workOrEndJob(Communicator& communicator, const std::string& what, const std::function<void()>& work) {
  int exit_code = 1;
  std::string message;
  try {
    work();
    return;
  } catch (const InterruptedError&) {
    // mpirun stops every rank when one fails or on Ctrl-C: say so briefly.
    std::fprintf(stderr, "vsd-sumo: rank %d of %d stopped by a signal\n", communicator.rank(), communicator.size());
    std::fflush(stderr);
    communicator.abort(130);
  } catch (const Error& error) {
    message = error.what();
  } catch (const std::exception& error) {
    exit_code = 3;
    message = fmt::format("internal error: {}", error.what());
  }
  std::fprintf(stderr, "vsd-sumo: error: rank %d of %d (%s): %s — the job ends; run it again to resume\n",
               communicator.rank(), communicator.size(), what.c_str(), message.c_str());
  std::fflush(stderr);
  communicator.abort(exit_code);
}

}  // namespace vsd::pipeline
