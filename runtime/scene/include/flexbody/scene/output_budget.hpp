#pragma once
// flexbody/scene/output_budget.hpp: what a run will write, estimated before its first step, against a budget of bytes
// and files (a ParaView frame every 10 steps of 1e-9 s is terabytes and millions of files, and nothing said
// so before the disk filled).

#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::scene {

/// The most a run may write into its output directory. fbsim's defaults: 10 GB and 100 000 files.
struct OutputBudget {
  double bytes = 10e9;
  double files = 1e5;
};

/// One part of a run's outputs: the CSV files, or one body's ParaView series.
struct OutputPart {
  std::string what;   ///< "CSV outputs (3 files)", "paraview body 'bracket'"
  std::string where;  ///< the scene lines that set its size ("scene.yaml:14"), for the refusal
  double rows = 0.0;  ///< rows per CSV file, or frames of the series
  double bytes = 0.0, files = 0.0;
};

/// What a run will write: its parts (estimated: a CSV value takes at most 24 characters and its comma, a ParaView
/// frame its arrays in base64 and its XML).
struct OutputEstimate {
  std::vector<OutputPart> parts;
  [[nodiscard]] double bytes() const;
  [[nodiscard]] double files() const;
};

/// A run refused before its first step because its estimate is over the budget; what() is one line naming the
/// scene lines that set the largest part, the estimate and the budget.
class OutputBudgetError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Throws OutputBudgetError when `estimate` is over `budget`; `step_where` names the line of the integrator's step.
void check_output_budget(const OutputEstimate& estimate, const OutputBudget& budget, const std::string& step_where);

/// A size as people write it: "10 GB", "500MB", "2 TiB", "1e9" (bytes); kB, MB, GB, TB are powers of 1000, KiB, MiB,
/// GiB, TiB of 1024. Throws std::invalid_argument naming the text.
[[nodiscard]] double parse_size(const std::string& text);
/// "8.8 GB", "512 kB", "900 B": three significant digits, powers of 1000.
[[nodiscard]] std::string format_size(double bytes);

}  // namespace flexbody::scene
