#pragma once
// Running fbprep and fbsim as a user does, from the tests: exit code, stdout and stderr.

#include <filesystem>
#include <string>
#include <vector>

namespace flexbody::test {

struct CliRun {
  int exit_code = -1;
  std::string out, err;
};

/// Runs `fbprep ARGUMENTS` (a shell word list) in `dir`; stdout and stderr go to dir/stdout.txt and
/// dir/stderr.txt, which are read back.
[[nodiscard]] CliRun run_fbprep(const std::filesystem::path& dir, const std::string& arguments);
/// The same for `fbsim ARGUMENTS`.
[[nodiscard]] CliRun run_fbsim(const std::filesystem::path& dir, const std::string& arguments);

/// The whole content of a text file.
[[nodiscard]] std::string slurp(const std::filesystem::path& path);

/// The numbers of a CSV file written by fbsim (one header line), row by row.
[[nodiscard]] std::vector<std::vector<double>> read_csv_numbers(const std::filesystem::path& path);

/// Writes `text` to a new file (replacing it).
void write_text(const std::filesystem::path& path, const std::string& text);

}  // namespace flexbody::test
