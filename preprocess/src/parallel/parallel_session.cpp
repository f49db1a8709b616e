#include "flexbody/preprocess/parallel_session.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <memory>
#include <stdexcept>

#ifdef FLEXBODY_WITH_SLEPC
#include "distributed_shift_invert.hpp"
#include "petsc_runtime.hpp"
#endif

namespace flexbody::preprocess {

#ifdef FLEXBODY_WITH_SLEPC

ParallelSession::ParallelSession() {
  if (parallel::launched_by_mpi_launcher()) {
    parallel::initialize();
    rank_ = parallel::rank();
    ranks_ = parallel::size();
  }
}

ParallelSession::~ParallelSession() {
  if (rank_ == 0 && ranks_ > 1) parallel::send_command(parallel::Command::stop);
  parallel::finalize();
}

int ParallelSession::serve() {
  using parallel::Command;
  std::unique_ptr<parallel::DistributedShiftInvert> system;
  while (true) {
    const Command command = parallel::receive_command();
    // Errors are agreed on by every rank (parallel::collective); rank 0 reports them.
    try {
      switch (command) {
        case Command::stop: return 0;
        case Command::create:
          parallel::collective([&] { system = std::make_unique<parallel::DistributedShiftInvert>(nullptr, nullptr, nullptr); });
          break;
        case Command::set_shift: parallel::collective([&] { system->set_shift(0.0); }); break;
        case Command::eigenpairs: parallel::collective([&] { (void)system->eigenpairs(0, 0, 0.0, 0, nullptr); }); break;
        case Command::solve: parallel::collective([&] { system->solve(nullptr, nullptr); }); break;
        case Command::destroy: system.reset(); break;
      }
    } catch (const std::exception&) {  // NOLINT(bugprone-empty-catch): rank 0 reports the agreed error
    }
  }
}

int parallel_ranks() { return parallel::size(); }

#else

namespace {
// Rank and size from the launcher's environment (Open MPI; MPICH/PMI), without MPI.
int environment_value(const char* open_mpi, const char* pmi, int fallback) {
  for (const char* name : {open_mpi, pmi})
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return fallback;
}
}  // namespace

ParallelSession::ParallelSession() {
  ranks_ = environment_value("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", 1);
  rank_ = environment_value("OMPI_COMM_WORLD_RANK", "PMI_RANK", 0);
  if (ranks_ > 1 && rank_ == 0)
    throw std::runtime_error(fmt::format("started on {} MPI ranks, but this build has no MPI backend (configure with "
                                         "-DFLEXBODY_WITH_SLEPC=ON), and every rank would run the whole job",
                                         ranks_));
}

ParallelSession::~ParallelSession() = default;

int ParallelSession::serve() { return 1; }

int parallel_ranks() { return 1; }

#endif

}  // namespace flexbody::preprocess
