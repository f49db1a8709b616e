// inspect_command.cpp: `fbprep inspect FILE.fbh5 [--json]`: read a body file (with every check of the
// reader) and print what it holds.
#include "cli_common.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/body_summary.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace flexbody::cli {

int inspect_command(int argc, char** argv) {
  CLI::App app{"fbprep inspect: check a flexible body file (*.fbh5) and print what it holds."};
  app.name("fbprep inspect");
  std::string file;
  bool json = false;
  app.add_option("FILE", file, "body file to read")->required();
  app.add_flag("--json", json, "print one JSON object on stdout instead of the report");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep inspect --help)", kBadCommandLine);
  }
  try {
    const format::BodyData body = format::read_body_file(file);
    if (json) std::cout << preprocess::body_json(body, file) << '\n';
    else std::cout << preprocess::body_report(body, file);
  } catch (const std::exception& e) {
    return fail_reading(e);
  }
  return 0;
}

}  // namespace flexbody::cli
