// fbprep as a library: run_fbprep runs one pass of the stages in prep_pass.hpp, or two when the error estimate asks
// for a refined mesh (refinement_pass.hpp).
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "prep_pass.hpp"
#include "refinement_pass.hpp"

#include "flexbody/format/body_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <exception>

namespace flexbody::preprocess {
namespace {

using Clock = std::chrono::steady_clock;

// Records a stage's wall time and the peak memory so far in the summary when it ends (not when it throws: the
// summary is not reported then).
class StageTimer {
 public:
  StageTimer(PrepSummary& summary, std::string name) : summary_(summary), name_(std::move(name)), start_(Clock::now()) {}
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;
  ~StageTimer() {
    if (std::uncaught_exceptions() > exceptions_) return;
    summary_.stages.push_back({name_, std::chrono::duration<double>(Clock::now() - start_).count(), peak_memory_mb()});
  }

 private:
  PrepSummary& summary_;
  std::string name_;
  Clock::time_point start_;
  int exceptions_ = std::uncaught_exceptions();
};

void check_output_location(const PrepOptions& options) {
  const std::filesystem::path& output = options.output;
  if (output.empty()) throw std::invalid_argument("no output file given (-o FILE.fbh5)");
  // The same file by any path (a symbolic or hard link, a relative path): writing would replace it.
  for (const auto& [input, what] : {std::pair{options.input, "the input"}, std::pair{options.spec, "the body spec"}}) {
    std::error_code same;
    if (!input.empty() && std::filesystem::equivalent(input, output, same))
      throw std::invalid_argument(fmt::format("{}: the output would overwrite {} {}; choose another output (-o)",
                                              output.string(), what, input.string()));
  }
  const std::filesystem::path directory = output.has_parent_path() ? output.parent_path() : ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec))
    throw std::invalid_argument(fmt::format("{}: the output directory does not exist", directory.string()));
  if (std::filesystem::is_directory(output, ec))
    throw std::invalid_argument(fmt::format("{}: the output is a directory, not a file", output.string()));
  if (std::filesystem::exists(output, ec) && !std::filesystem::is_regular_file(output, ec))
    throw std::invalid_argument(fmt::format("{}: the output exists and is not a regular file (a device, a pipe or a "
                                            "socket); choose another output (-o)", output.string()));
  if (std::filesystem::exists(output, ec) && !std::filesystem::is_empty(output, ec) &&
      !format::begins_like_body_file(output))
    throw std::invalid_argument(fmt::format(
        "{}: the output exists and is not a body file (it does not begin with a flexbody seal or HDF5's signature); "
        "fbprep replaces only body files: remove it or choose another output (-o)", output.string()));
}

}  // namespace

std::string_view to_string(ReductionKind kind) {
  return kind == ReductionKind::free_free ? "free-free" : "craig-bampton";
}

namespace {

// What a pass refuses before any work: a material out of range, an output it must not replace, and a reduction its
// interfaces do not fit (a free-free basis cannot honour a rigid tie, and Craig-Bampton needs one).
void check_request(const PrepOptions& options) {
  check_material(options.material);
  check_output_location(options);
  const bool any_rbe2 = std::any_of(options.interfaces.begin(), options.interfaces.end(),
                                    [](const InterfaceRequest& i) { return i.coupling == "rbe2"; });
  if (options.reduction == ReductionKind::free_free)
    for (const InterfaceRequest& i : options.interfaces)
      if (i.coupling == "rbe2")
        throw std::invalid_argument(fmt::format(
            "interface '{}': coupling rbe2 ties its nodes rigidly, which changes the modes; free-free modes take "
            "rbe3 interfaces only (use reduction kind craig-bampton for rbe2)", i.name));
  if (options.reduction == ReductionKind::craig_bampton) {
    if (!any_rbe2)
      throw std::invalid_argument("craig-bampton reduction: no rbe2 interface; its constraint modes need at least one");
    if (options.modes.modes < 1 && !(options.modes.fmax_hz > 0.0))
      throw std::invalid_argument("craig-bampton reduction: give the number of fixed-interface modes (modes) or fmax");
  }
}

// One pass from the input to the body file, stage by stage (prep_pass.hpp), each timed. With `refine` (the first pass
// of a mesh fbprep may refine), a first frequency estimated beyond options.error_target stops the pass after the
// estimate, with the second mesh's sizes in *refine and the plan in the returned summary's `refinement`.
PrepSummary run_pass(const PrepOptions& options, std::shared_ptr<const MeshSizeField>* refine) {
  const auto start = Clock::now();
  check_request(options);
  PrepSummary summary;
  summary.input = options.input;
  summary.output = options.output;
  summary.material = options.material;
  PrepPass pass(options, summary);
  {
    const StageTimer timer(summary, "mesh");
    mesh_stage(pass);
  }
  {
    const StageTimer timer(summary, "assembly");
    assembly_stage(pass);
  }
  body_frame_stage(pass);  // these two between the timed stages, as they always were
  interface_stage(pass);
  bool whole = true;
  {
    const StageTimer timer(summary, "modes");
    whole = modes_stage(pass, refine);
  }
  if (!whole) {  // stopped for a refined mesh
    summary.refinement->first_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return summary;
  }
  {
    const StageTimer timer(summary, "gcms");
    gcms_stage(pass);
  }
  {
    const StageTimer timer(summary, "recovery");
    recovery_stage(pass);
  }
  {
    const StageTimer timer(summary, "write");
    write_stage(pass);
  }
  summary.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.peak_memory_mb = peak_memory_mb();
  return summary;
}

}  // namespace

PrepSummary run_fbprep(const PrepOptions& options) {
  if (!(options.error_target >= 0.0 && options.error_target < 1.0))
    throw std::invalid_argument(fmt::format("error target {} is not a relative frequency error in [0, 1) (0: no "
                                            "refinement)", options.error_target));
  const auto start = Clock::now();
  std::shared_ptr<const MeshSizeField> sizes;
  PrepSummary first = run_pass(options, detail::refinement_allowed(options) ? &sizes : nullptr);
  if (!sizes) return first;
  PrepOptions refined = options;
  refined.mesh.size_field = std::move(sizes);
  // The second mesh may fail where the first did not (memory, the volume check): say which mesh, and the way back.
  const std::string second = fmt::format(" (on the mesh refined by the error estimate: the first mesh's frequency was "
                                         "estimated {:.1f} % off; --error-target 0 keeps the first mesh)",
                                         100.0 * first.refinement->first_estimate);
  PrepSummary summary;
  try {
    summary = run_pass(refined, nullptr);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(e.what() + second);
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(options.input.filename().string() + ": out of memory" + second);
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what() + second);
  }
  summary.refinement = first.refinement;
  for (StageRecord& stage : first.stages) stage.name += " (first mesh)";
  summary.stages.insert(summary.stages.begin(), first.stages.begin(), first.stages.end());
  summary.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

}  // namespace flexbody::preprocess
