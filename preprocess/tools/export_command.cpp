// export_command.cpp: `fbprep export-vtu FILE.fbh5 -o DIR`: the mesh with every mode shape and its
// stresses, the GCMS fields and the interfaces as a ParaView file, DIR/<name>.vtu.
#include "cli_common.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/vtu_export.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace flexbody::cli {

int export_command(int argc, char** argv) {
  CLI::App app{"fbprep export-vtu: write a body file's mesh, mode shapes with their stresses, GCMS fields and "
               "interfaces as a VTK unstructured grid (.vtu) for ParaView."};
  app.name("fbprep export-vtu");
  std::string file, directory;
  app.add_option("FILE", file, "body file to read")->required();
  app.add_option("-o,--output", directory, "directory to write FILE's name with .vtu into (created if missing)")
      ->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep export-vtu --help)", kBadCommandLine);
  }
  try {
    const format::BodyData body = format::read_body_file(file);
    std::filesystem::create_directories(directory);
    const std::filesystem::path target =
        std::filesystem::path(directory) / std::filesystem::path(file).filename().replace_extension(".vtu");
    preprocess::write_body_vtu(body, target);
    std::cout << target.string() << '\n';
  } catch (const std::exception& e) {
    return fail_reading(e);
  }
  return 0;
}

}  // namespace flexbody::cli
