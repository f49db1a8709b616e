#include "petsc_runtime.hpp"

#include "mumps_status.hpp"

#include <slepcsys.h>

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>

namespace flexbody::preprocess::parallel {
namespace {

bool g_initialized = false;
bool g_finalized = false;
// The specific message of the last PETSc error on this rank ("MUMPS error in numerical factorization phase:
// INFOG(1)=-9, ..."); PetscErrorMessage() knows only the generic text of the code.
std::string g_last_error;

PetscErrorCode keep_message(MPI_Comm, int, const char*, const char*, PetscErrorCode code, PetscErrorType type,
                            const char* message, void*) {
  if (type == PETSC_ERROR_INITIAL) g_last_error = message != nullptr ? message : "";
  return code;
}

}  // namespace

bool launched_by_mpi_launcher() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(variable) != nullptr) return true;
  return false;
}

void initialize() {
  if (g_initialized) return;
  if (g_finalized) throw std::logic_error("SLEPc: initialized again after finalize");
  // argc = 0: PETSc reads no command-line options (fbprep's are not PETSc's); PETSC_OPTIONS still applies.
  int argc = 0;
  char** argv = nullptr;
  if (SlepcInitialize(&argc, &argv, nullptr, nullptr) != 0)
    throw std::runtime_error("SLEPc: initialization failed (MPI could not start)");
  g_initialized = true;
  // A program that used the slepc backend without a ParallelSession still ends MPI properly.
  std::atexit(finalize);
  // One error line from us, not PETSc's traceback on stderr.
  check(PetscPushErrorHandler(keep_message, nullptr), "PetscPushErrorHandler");
}

bool initialized() { return g_initialized; }

void finalize() {
  if (!g_initialized) return;
  PetscPopErrorHandler();
  SlepcFinalize();
  g_initialized = false;
  g_finalized = true;
}

int rank() {
  if (!g_initialized) return 0;
  int r = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &r);
  return r;
}

int size() {
  if (!g_initialized) return 1;
  int s = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &s);
  return s;
}

void check(PetscErrorCode code, const char* what) {
  if (code == 0) {
    g_last_error.clear();
    return;
  }
  std::string text = g_last_error;
  g_last_error.clear();
  if (text.empty()) {
    const char* generic = nullptr;
    PetscErrorMessage(code, &generic, nullptr);
    text = generic != nullptr ? generic : "unknown error";
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  // MUMPS's status in words, with the ways out (mumps_status.hpp): "INFOG(1)=-9" alone tells a user nothing.
  throw std::runtime_error(
      detail::with_mumps_words(fmt::format("{}: {} (PETSc error {})", what, text, static_cast<int>(code))));
}

void send_command(Command command) {
  int value = static_cast<int>(command);
  MPI_Request request;
  MPI_Ibcast(&value, 1, MPI_INT, 0, PETSC_COMM_WORLD, &request);
  MPI_Wait(&request, MPI_STATUS_IGNORE);
}

Command receive_command() {
  int value = -1;
  MPI_Request request;
  MPI_Ibcast(&value, 1, MPI_INT, 0, PETSC_COMM_WORLD, &request);
  // Poll: 1 ms latency at most, against a whole core taken by MPI's busy wait for the rest of the run.
  for (int done = 0;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (value < 0 || value > static_cast<int>(Command::destroy))
    throw std::logic_error(fmt::format("MPI worker: unknown command {} from rank 0", value));
  return static_cast<Command>(value);
}

void agree(const std::string& error) {
  const int ranks = size();
  const int mine = error.empty() ? ranks : rank();
  int first_failed = ranks;
  MPI_Allreduce(&mine, &first_failed, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD);
  if (first_failed == ranks) return;
  // The lowest failing rank's message, to every rank.
  std::string message = rank() == first_failed ? error : std::string();
  int length = static_cast<int>(message.size());
  MPI_Bcast(&length, 1, MPI_INT, first_failed, PETSC_COMM_WORLD);
  message.resize(static_cast<std::size_t>(length));
  MPI_Bcast(message.data(), length, MPI_CHAR, first_failed, PETSC_COMM_WORLD);
  if (first_failed != 0) message = fmt::format("{} (on MPI rank {})", message, first_failed);
  throw std::runtime_error(message);
}

}  // namespace flexbody::preprocess::parallel
