#include "cli_run.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace flexbody::test {

std::string slurp(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

std::vector<std::vector<double>> read_csv_numbers(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // the header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) row.push_back(std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

namespace {

CliRun run_tool(const std::filesystem::path& dir, const char* executable, const std::string& arguments) {
  const std::string command =
      fmt::format("cd '{}' && '{}' {} > stdout.txt 2> stderr.txt", dir.string(), executable, arguments);
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir / "stdout.txt"), slurp(dir / "stderr.txt")};
}

}  // namespace

CliRun run_fbprep(const std::filesystem::path& dir, const std::string& arguments) {
  return run_tool(dir, FLEXBODY_FBPREP, arguments);
}

CliRun run_fbsim(const std::filesystem::path& dir, const std::string& arguments) {
  return run_tool(dir, FLEXBODY_FBSIM, arguments);
}

}  // namespace flexbody::test
