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

CliRun run_fbprep(const std::filesystem::path& dir, const std::string& arguments) {
  const std::string command = fmt::format("cd '{}' && '{}' {} > stdout.txt 2> stderr.txt", dir.string(),
                                          FLEXBODY_FBPREP, arguments);
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir / "stdout.txt"), slurp(dir / "stderr.txt")};
}

}  // namespace flexbody::test
