// fbprep: CAD (STEP, IGES, BREP, .geo) or a tetrahedral .msh -> flexible body file (*.fbh5), and tools
// for body files.
//
//   fbprep part.step -o part.fbh5 --material steel --modes 12
//   fbprep inspect part.fbh5 [--json]
//
// The first argument picks the command; anything else is the input of the main command (a part file
// literally named "inspect" is given as ./inspect).
#include "cli_common.hpp"

#include <string_view>

int main(int argc, char** argv) {
  if (argc >= 2 && std::string_view(argv[1]) == "inspect") return flexbody::cli::inspect_command(argc - 1, argv + 1);
  return flexbody::cli::prep_command(argc, argv);
}
