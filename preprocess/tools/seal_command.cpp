// seal_command.cpp: `fbprep seal FILE.fbh5 [-o OUT.fbh5]`: read a body file with every check of the reader
// but without requiring its seal, and write it again, sealed, in the current format version (atomically;
// OUT defaults to FILE). For a file edited on purpose (h5py) and for version-3 files (SCHEMA.md, "Seal").
#include "cli_common.hpp"

#include "flexbody/format/body_file.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace flexbody::cli {
namespace {

std::string describe_seal(const format::BodyData& body) {
  if (body.sealed) return "its seal matched";
  return body.format_version == format::kUnsealedFormatVersion ? "unsealed" : "without a matching seal";
}

}  // namespace

int seal_command(int argc, char** argv) {
  CLI::App app{"fbprep seal: check a body file (*.fbh5) that was edited on purpose or written by an earlier fbprep "
               "(format version 3) with every check of the reader, and write it again sealed in the current "
               "format version, so that readers accept it."};
  app.name("fbprep seal");
  std::string file, output;
  bool quiet = false;
  app.add_option("FILE", file, "body file to check and seal")->required();
  app.add_option("-o,--output", output, "body file to write (default: FILE itself, replaced atomically)");
  app.add_flag("--quiet", quiet, "print nothing on success");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep seal --help)", kBadCommandLine);
  }
  const std::filesystem::path target = output.empty() ? std::filesystem::path(file) : std::filesystem::path(output);
  // Like fbprep -o: an existing OUT is replaced only when it is a body file (or empty). OUT naming FILE itself
  // (by any path) is the in-place re-seal that leaving -o out does.
  std::error_code error;
  const bool in_place = output.empty() || std::filesystem::equivalent(file, target, error);
  if (!in_place && std::filesystem::exists(target, error) && !std::filesystem::is_directory(target, error) &&
      !std::filesystem::is_regular_file(target, error))
    return fail(target.string() + ": the output exists and is not a regular file (a device, a pipe or a socket); "
                                  "choose another output (-o)", kBadCommandLine);
  if (!in_place && std::filesystem::exists(target, error) && !std::filesystem::is_directory(target, error) &&
      !std::filesystem::is_empty(target, error) && !format::begins_like_body_file(target))
    return fail(target.string() + ": the output exists and is not a body file (it does not begin with a flexbody seal "
                                  "or HDF5's signature); fbprep seal replaces only body files: remove it or choose "
                                  "another output (-o)", kBadCommandLine);
  try {
    format::ReadOptions options;
    options.require_seal = false;  // what this command is for; every other check still runs
    const format::BodyData body = format::read_body_file(file, options);
    format::write_body_file(body, target);
    if (!quiet) {
      std::cout << file << " (format version " << body.format_version << ", " << describe_seal(body)
                << "): every check passed; written sealed, format version " << format::kFormatVersion << ", to "
                << target.string() << '\n';
    }
  } catch (const std::exception& e) {
    return fail(e.what(), kFailed);
  }
  return 0;
}

}  // namespace flexbody::cli
