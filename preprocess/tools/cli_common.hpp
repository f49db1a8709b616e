#pragma once
// cli_common.hpp: what every fbprep command shares: exit codes and the one-line error.
//
// Errors: one line on stderr and no file under the output name. Exit code 2 when the command line asks
// for something impossible (an unknown option, a bad value, a request the part cannot meet: library
// functions signal these with std::invalid_argument) and when a body file's seal shows it was damaged or
// modified after it was written (format::BodyFileDamaged), 1 when reading the input or computing fails.

#include "flexbody/format/body_file.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

namespace flexbody::cli {

inline constexpr int kBadCommandLine = 2;
inline constexpr int kFailed = 1;

/// Prints "fbprep: error: <message>" as one line on stderr (gmsh and OpenCASCADE messages may span
/// lines) and returns `code`.
inline int fail(std::string message, int code) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::fflush(stdout);
  std::fprintf(stderr, "fbprep: error: %s\n", message.c_str());
  return code;
}

/// The one-line error for a failure to read or use a body file: exit code 2 for a file whose seal does not
/// match (format::BodyFileDamaged), 1 for anything else.
inline int fail_reading(const std::exception& error) {
  const bool damaged = dynamic_cast<const format::BodyFileDamaged*>(&error) != nullptr;
  return fail(error.what(), damaged ? kBadCommandLine : kFailed);
}

/// `fbprep INPUT ...`: mesh, assemble, modes, GCMS constants, body file.
int prep_command(int argc, char** argv);
/// `fbprep inspect FILE.fbh5 [--json]`: what a body file holds.
int inspect_command(int argc, char** argv);
/// `fbprep export-vtu FILE.fbh5 -o DIR`: the body for ParaView.
int export_command(int argc, char** argv);
/// `fbprep seal FILE.fbh5 [-o OUT.fbh5]`: check an edited or version-3 body file and write it sealed.
int seal_command(int argc, char** argv);
/// `fbprep list-surfaces INPUT [--unit U] [--mesh-size L] [--json]`: CAD surface tags for body specs.
int list_surfaces_command(int argc, char** argv);

}  // namespace flexbody::cli
