#pragma once
// flexbody/runtime/paraview_series.hpp: one body's deformed surface over time as a ParaView series: a .pvd
// collection and one .vtu per frame, with the elastic displacements and, where the body file recovers them,
// the stresses.

#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace flexbody::runtime {

/// Writes DIRECTORY/NAME.pvd and DIRECTORY/NAME/NAME_000000.vtu, … : the body's surface triangles at their
/// world positions r_i = τ + A X̄_i + Σ_f Ῡ'_f(i) ξ_f (Eq. 61), with point data
/// - "displacement" [m]: the elastic displacement in world axes, Σ_f Ῡ'_f(i) ξ_f = A ū_i;
/// - with stresses: "stress" [Pa], the nodal Cauchy stress in world axes A σ̄ Aᵀ with σ̄ = S ξ̄ from the body
///   file's recovery regions (6 components, ParaView's order XX, YY, ZZ, XY, YZ, XZ), and "von_mises" [Pa].
/// Each frame is written atomically and the .pvd is rewritten after it, so the series on disk is complete
/// up to the last frame written, also after a run that stopped.
class ParaViewSeries {
 public:
  /// `stresses`: write them. Throws std::invalid_argument if `name` is not a plain file name, or naming the body
  /// if the model has no surface triangles, or if stresses are asked of a flexible body whose recovery regions leave surface nodes out
  /// (a rigid body's stresses are zero and are not written).
  ParaViewSeries(std::filesystem::path directory, std::string name, const BodyModel& model, bool stresses);

  /// Writes the frame of body coordinates q_b ([τ, a, ξ], BodyModel::coordinate_count()) at time t [s].
  /// Throws std::runtime_error naming the file if it cannot be written or a value is not finite.
  void write(double t, const Eigen::VectorXd& q_b);

  /// The path of the first of the frames at `times` (this series' first frames) that is not a file, or "".
  [[nodiscard]] std::string missing_frame(const std::vector<double>& times) const;
  /// Continues a series whose first frames, at `times` and of `bytes` in all, a stopped run wrote (a checkpoint's):
  /// the collection is rewritten to list just them, and the next frame takes the next number. Throws
  /// std::runtime_error naming the first frame file that is missing (missing_frame).
  void resume(const std::vector<double>& times, double bytes);
  /// The times of the frames written so far [s], in order.
  [[nodiscard]] std::vector<double> frame_times() const;

  [[nodiscard]] const std::filesystem::path& collection() const { return collection_; }
  [[nodiscard]] std::size_t frame_count() const { return frames_.size(); }
  /// The time of the last frame written (−inf before the first).
  [[nodiscard]] double last_time() const { return frames_.empty() ? -std::numeric_limits<double>::infinity() : frames_.back().first; }
  [[nodiscard]] Eigen::Index surface_node_count() const { return nodes_.rows(); }
  [[nodiscard]] bool writes_stresses() const { return stress_modes_.rows() > 0; }
  /// The size of one frame's file [bytes]: its arrays in base64 with their headers, and about 1 kB of XML.
  [[nodiscard]] double frame_bytes() const;
  /// The bytes of the frames written so far (their files' sizes; the .pvd collection not counted).
  [[nodiscard]] double bytes_written() const { return bytes_written_; }

 private:
  std::filesystem::path directory_, collection_;
  std::string name_;
  Eigen::VectorXi node_index_;                         ///< the surface's body nodes, ascending
  Eigen::Matrix<double, Eigen::Dynamic, 3> nodes_;     ///< X̄ of those nodes
  Eigen::MatrixXd fields_;                             ///< Ῡ' rows of those nodes (n_s x n_f); empty if sparse
  /// The same for the full-order body (full_order.hpp), whose Ῡ' has a few entries per row (n_s x n_f).
  Eigen::SparseMatrix<double, Eigen::RowMajor> sparse_fields_;
  Eigen::Index field_count_ = 0;
  Eigen::MatrixXd stress_modes_;                       ///< S rows of those nodes (6 n_s x 3 n_f), or empty
  std::vector<std::int64_t> triangles_;                ///< surface triangles in surface-node numbering
  std::vector<std::pair<double, std::string>> frames_;
  double bytes_written_ = 0.0;
};

}  // namespace flexbody::runtime
