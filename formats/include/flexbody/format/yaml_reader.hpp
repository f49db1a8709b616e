#pragma once
// flexbody/format/yaml_reader.hpp: typed reading of the project's YAML files (body specs, scenes) with errors
// that name the file and line: "<file>:<line>: <problem>" (lines from 1), as std::invalid_argument.
// Header-only, in its own target flexbody::yaml (yaml-cpp, fmt), so flexbody::format itself stays Eigen + HDF5.

#include <Eigen/Core>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>

namespace flexbody::format {

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  /// The file's document; a missing file or a YAML syntax error is one error naming the file (and line).
  [[nodiscard]] YAML::Node load(const std::string& what) const {
    try {
      return YAML::LoadFile(file_);
    } catch (const YAML::BadFile&) {
      throw std::invalid_argument(fmt::format("{}: cannot open the {}: {}", file_, what, why_unreadable(file_)));
    } catch (const YAML::Exception& e) {
      throw std::invalid_argument(fmt::format("{}:{}: {}", file_, e.mark.line + 1, e.msg));
    }
  }

  /// Why `file` cannot be opened for reading, as the system says it ("No such file or directory", "Permission
  /// denied", "Is a directory").
  [[nodiscard]] static std::string why_unreadable(const std::string& file) {
    std::error_code error;
    if (std::filesystem::is_directory(file, error)) return std::make_error_code(std::errc::is_a_directory).message();
    errno = 0;
    std::FILE* probe = std::fopen(file.c_str(), "rb");
    if (probe == nullptr) return std::generic_category().message(errno);
    std::fclose(probe);
    return "unreadable";
  }

  /// "<file>:<line>" of a node, or "<file>" for one that came from no file's text.
  [[nodiscard]] std::string at(const YAML::Node& node) const {
    const int line = node.IsDefined() ? node.Mark().line + 1 : 0;
    return line > 0 ? fmt::format("{}:{}", file_, line) : file_;
  }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& message) const {
    const int line = at.IsDefined() ? at.Mark().line + 1 : 0;
    throw std::invalid_argument(line > 0 ? fmt::format("{}:{}: {}", file_, line, message)
                                         : fmt::format("{}: {}", file_, message));
  }

  // A map whose keys are all in `allowed`, each at most once.
  void expect_map(const YAML::Node& node, const std::string& what, std::initializer_list<const char*> allowed) const {
    if (!node.IsMap()) fail(node, fmt::format("{} must be a map of keys to values", what));
    std::set<std::string> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.Scalar();
      bool known = false;
      for (const char* k : allowed) known = known || key == k;
      if (!known) fail(it->first, fmt::format("unknown key '{}' in {}; expected {}", key, what, fmt::join(allowed, ", ")));
      if (!seen.insert(key).second) fail(it->first, fmt::format("key '{}' is repeated in {}", key, what));
    }
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, fmt::format("{} must be a single value", what));
    return node.Scalar();
  }

  double number(const YAML::Node& node, const std::string& what) const {
    const std::string value = text(node, what);
    for (const char* special : {".nan", ".NaN", ".NAN", ".inf", ".Inf", ".INF", "-.inf", "-.Inf", "-.INF", "+.inf"})
      if (value == special) fail(node, fmt::format("{} must be finite, got '{}'", what, value));  // YAML 1.2 floats
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(value.c_str(), &end);
    if (value.empty() || end != value.c_str() + value.size() || errno == ERANGE)
      fail(node, fmt::format("{} must be a number, got '{}'", what, value));
    if (!std::isfinite(x)) fail(node, fmt::format("{} must be finite, got '{}'", what, value));
    return x;
  }

  double positive(const YAML::Node& node, const std::string& what) const {
    const double x = number(node, what);
    if (!(x > 0.0)) fail(node, fmt::format("{} must be positive, got {}", what, x));
    return x;
  }

  int count(const YAML::Node& node, const std::string& what) const {
    const double x = number(node, what);
    if (x < 0 || x != std::floor(x) || x > 1e6) fail(node, fmt::format("{} must be a whole number >= 0, got {}", what, x));
    return static_cast<int>(x);
  }

  /// `true` or `false`, nothing else (YAML's yes/on/1 are refused: one spelling per meaning).
  bool truth(const YAML::Node& node, const std::string& what) const {
    const std::string t = text(node, what);
    if (t != "true" && t != "false") fail(node, fmt::format("{} must be true or false", what));
    return t == "true";
  }

  Eigen::Vector3d vector3(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() != 3) fail(node, fmt::format("{} must be a list of 3 numbers", what));
    return {number(node[0], what), number(node[1], what), number(node[2], what)};
  }

  YAML::Node required(const YAML::Node& map, const char* key, const std::string& what) const {
    const YAML::Node value = map[key];
    if (!value.IsDefined()) fail(map, fmt::format("{} needs '{}'", what, key));
    return value;
  }

 private:
  std::string file_;
};

}  // namespace flexbody::format
