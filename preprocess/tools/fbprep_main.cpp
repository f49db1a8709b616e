// fbprep: CAD (STEP, IGES, BREP, .geo) or a tetrahedral .msh -> flexible body file (*.fbh5), and tools
// for body files.
//
//   fbprep part.step -o part.fbh5 --material steel --modes 12
//   fbprep inspect part.fbh5 [--json]
//   fbprep export-vtu part.fbh5 -o DIR
//   fbprep seal part.fbh5 [-o sealed.fbh5]
//   fbprep list-surfaces part.step
//   mpirun -np 2 fbprep part.step --eigensolver slepc   (builds with -DFLEXBODY_WITH_SLEPC=ON)
//
// The first argument picks the command; anything else is the input of the main command (a part file
// literally named like a command is given as ./inspect).
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/parallel_session.hpp"
#include "cli_common.hpp"

#include <exception>
#include <optional>
#include <string_view>

int main(int argc, char** argv) {
  flexbody::format::skip_hdf5_cleanup_at_exit();  // one error line, nothing from HDF5 after it
  flexbody::format::remove_temporary_body_file_on_signal();  // Ctrl-C during a write leaves no .NAME.fbh5.tmp-*
  // Under mpirun, rank 0 runs the command and the other ranks serve its distributed eigen stage.
  std::optional<flexbody::preprocess::ParallelSession> session;
  try {
    session.emplace();
  } catch (const std::exception& e) {
    return flexbody::cli::fail(e.what(), flexbody::cli::kBadCommandLine);
  }
  if (session->is_worker()) return session->serve();
  const std::string_view command = argc >= 2 ? argv[1] : "";
  if (command == "inspect") return flexbody::cli::inspect_command(argc - 1, argv + 1);
  if (command == "export-vtu") return flexbody::cli::export_command(argc - 1, argv + 1);
  if (command == "seal") return flexbody::cli::seal_command(argc - 1, argv + 1);
  if (command == "list-surfaces") return flexbody::cli::list_surfaces_command(argc - 1, argv + 1);
  return flexbody::cli::prep_command(argc, argv);
}
