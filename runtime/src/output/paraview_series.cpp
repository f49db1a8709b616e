#include "flexbody/runtime/paraview_series.hpp"

#include "flexbody/format/vtk_xml.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/marker.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace flexbody::runtime {
namespace {

// ParaView's SymmetricTensor order XX, YY, ZZ, XY, YZ, XZ as (row, column) pairs.
constexpr std::array<std::array<int, 2>, 6> kParaViewComponents = {{{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}}};

// σ̄ from the stored Voigt order xx, yy, zz, xy, xz, yz (SCHEMA.md /recovery).
Eigen::Matrix3d tensor_of(const double* voigt) {
  Eigen::Matrix3d s;
  s << voigt[0], voigt[3], voigt[4],  //
      voigt[3], voigt[1], voigt[5],   //
      voigt[4], voigt[5], voigt[2];
  return s;
}

double von_mises_of(const Eigen::Matrix3d& s) {
  const Eigen::Matrix3d deviator = s - s.trace() / 3.0 * Eigen::Matrix3d::Identity();
  return std::sqrt(1.5 * deviator.squaredNorm());
}

std::string frame_name(const std::string& name, std::size_t frame) {
  char number[32];  // "_" + up to 20 digits + ".vtu"
  std::snprintf(number, sizeof number, "_%06zu.vtu", frame);
  return name + number;
}

}  // namespace

ParaViewSeries::ParaViewSeries(std::filesystem::path directory, std::string name, const BodyModel& model, bool stresses)
    : directory_(std::move(directory)), name_(std::move(name)) {
  if (name_.empty() || name_.find_first_of("/\\") != std::string::npos || name_ == "." || name_ == "..")
    throw std::invalid_argument("ParaView series '" + name_ + "': the name must be a plain file name");
  collection_ = directory_ / (name_ + ".pvd");
  if (model.surface_triangles.rows() == 0)
    throw std::invalid_argument(model.source + ": the body has no surface triangles to draw");
  // The surface's nodes, numbered in ascending order of their body node.
  std::vector<int> used(model.surface_triangles.data(), model.surface_triangles.data() + model.surface_triangles.size());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  if (used.front() < 0 || used.back() >= model.nodes.rows())
    throw std::invalid_argument(model.source + ": a surface triangle names a node outside the mesh");
  const Eigen::Index n_s = static_cast<Eigen::Index>(used.size());
  node_index_ = Eigen::Map<const Eigen::VectorXi>(used.data(), n_s);
  std::vector<Eigen::Index> local(static_cast<std::size_t>(model.nodes.rows()), -1);
  nodes_.resize(n_s, 3);
  field_count_ = model.field_count();
  if (!model.sparse) fields_.resize(n_s, field_count_);
  std::vector<Eigen::Triplet<double>> sparse_rows;  // a full-order body's: Ῡ' = I (node i is field i) or T's rows
  for (Eigen::Index j = 0; j < n_s; ++j) {
    local[static_cast<std::size_t>(node_index_(j))] = j;
    nodes_.row(j) = model.nodes.row(node_index_(j));
    if (!model.sparse) {
      fields_.row(j) = field_row(model, node_index_(j));
    } else if (model.sparse->fields.rows() == 0) {
      sparse_rows.emplace_back(j, node_index_(j), 1.0);
    } else {
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.sparse->fields, node_index_(j)); it; ++it)
        sparse_rows.emplace_back(j, it.col(), it.value());
    }
  }
  if (model.sparse) {
    sparse_fields_.resize(n_s, field_count_);
    sparse_fields_.setFromTriplets(sparse_rows.begin(), sparse_rows.end());
  }
  triangles_.reserve(static_cast<std::size_t>(model.surface_triangles.size()));
  for (Eigen::Index t = 0; t < model.surface_triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) triangles_.push_back(local[static_cast<std::size_t>(model.surface_triangles(t, k))]);

  if (stresses && !model.rigid()) {  // each surface node's rows of S, from the first region that holds it
    stress_modes_.resize(6 * n_s, 3 * model.field_count());
    std::vector<bool> found(static_cast<std::size_t>(n_s), false);
    for (const format::RecoveryRegion& region : model.recovery)
      for (Eigen::Index j = 0; j < region.nodes.size(); ++j) {
        const Eigen::Index s = local[static_cast<std::size_t>(region.nodes(j))];
        if (s < 0 || found[static_cast<std::size_t>(s)]) continue;
        stress_modes_.middleRows<6>(6 * s) = region.stress_modes.middleRows<6>(6 * j);
        found[static_cast<std::size_t>(s)] = true;
      }
    const auto covered = std::count(found.begin(), found.end(), true);
    if (covered < n_s)
      throw std::invalid_argument(model.source + ": its output regions recover stresses at " + std::to_string(covered) +
                                  " of the " + std::to_string(n_s) +
                                  " surface nodes; re-run fbprep with an output region that holds the surface "
                                  "(or leave output_regions out), or ask for no stresses");
  }
}

void ParaViewSeries::write(double t, const Eigen::VectorXd& q_b) {
  const Eigen::Index n_s = nodes_.rows(), n_f = field_count_;
  if (q_b.size() != 12 + 3 * n_f)
    throw std::invalid_argument(name_ + ": " + std::to_string(q_b.size()) + " body coordinates for a body of " +
                                std::to_string(12 + 3 * n_f));
  if (frames_.empty()) std::filesystem::create_directories(directory_ / name_);
  const Eigen::Matrix3d a = orientation_of(q_b);
  const Eigen::Vector3d tau = q_b.head<3>();
  const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> xi(q_b.data() + 12, 3, n_f);

  std::vector<double> points(static_cast<std::size_t>(3 * n_s)), displacement(static_cast<std::size_t>(3 * n_s));
  for (Eigen::Index j = 0; j < n_s; ++j) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();  // Σ_f Ῡ'_f(i) ξ_f, world axes
    if (sparse_fields_.rows() == 0) {
      u.noalias() = xi * fields_.row(j).transpose();
    } else {
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(sparse_fields_, j); it; ++it)
        u += it.value() * xi.col(it.col());
    }
    const Eigen::Vector3d r = tau + a * nodes_.row(j).transpose() + u;
    for (int k = 0; k < 3; ++k) {
      points[static_cast<std::size_t>(3 * j + k)] = r(k);
      displacement[static_cast<std::size_t>(3 * j + k)] = u(k);
    }
  }
  const std::string file = frame_name(name_, frames_.size());
  format::VtuWriter out(directory_ / name_ / file, n_s, static_cast<std::int64_t>(triangles_.size() / 3));
  out.point_array("displacement", 3, displacement);
  if (writes_stresses()) {
    const Eigen::VectorXd sigma_bar = stress_modes_ * body_frame_coordinates(a, q_b.tail(3 * n_f));
    std::vector<double> stress(static_cast<std::size_t>(6 * n_s)), mises(static_cast<std::size_t>(n_s));
    for (Eigen::Index j = 0; j < n_s; ++j) {
      const Eigen::Matrix3d s = a * tensor_of(sigma_bar.data() + 6 * j) * a.transpose();
      for (std::size_t c = 0; c < kParaViewComponents.size(); ++c)
        stress[static_cast<std::size_t>(6 * j) + c] = s(kParaViewComponents[c][0], kParaViewComponents[c][1]);
      mises[static_cast<std::size_t>(j)] = von_mises_of(s);
    }
    out.point_array("stress", 6, stress);
    out.point_array("von_mises", 1, mises);
  }
  out.points(points);
  out.cells(triangles_, 3, format::kVtkTriangle);
  out.commit();
  std::error_code unknown;  // a size that cannot be read counts 0: the frame is written, the count is a report
  const std::uintmax_t size = std::filesystem::file_size(directory_ / name_ / file, unknown);
  bytes_written_ += unknown ? 0.0 : static_cast<double>(size);
  frames_.emplace_back(t, name_ + "/" + file);
  format::write_pvd(collection_, frames_);
}

std::string ParaViewSeries::missing_frame(const std::vector<double>& times) const {
  for (std::size_t k = 0; k < times.size(); ++k) {
    const std::filesystem::path path = directory_ / name_ / frame_name(name_, k);
    if (std::error_code unknown; !std::filesystem::is_regular_file(path, unknown)) return path.string();
  }
  return {};
}

void ParaViewSeries::resume(const std::vector<double>& times, double bytes) {
  if (const std::string missing = missing_frame(times); !missing.empty())
    throw std::runtime_error(missing + ": a frame of the checkpoint's series is missing");
  frames_.clear();
  for (const double t : times) frames_.emplace_back(t, name_ + "/" + frame_name(name_, frames_.size()));
  bytes_written_ = bytes;
  if (!frames_.empty()) format::write_pvd(collection_, frames_);
}

std::vector<double> ParaViewSeries::frame_times() const {
  std::vector<double> times;
  times.reserve(frames_.size());
  for (const auto& frame : frames_) times.push_back(frame.first);
  return times;
}

double ParaViewSeries::frame_bytes() const {
  // An array: base64 of an 8-byte length header and the data (format/vtk_xml.cpp).
  auto array = [](double raw) { return 4.0 * std::ceil((8.0 + raw) / 3.0); };
  const auto n_s = static_cast<double>(nodes_.rows());
  const auto n_t = static_cast<double>(triangles_.size() / 3);
  const double doubles = 8.0 * n_s;
  double bytes = 1000.0 + array(3 * doubles) /* displacement */ + array(3 * doubles) /* points */ +
                 array(3 * 8 * n_t) /* connectivity */ + array(8 * n_t) /* offsets */ + array(n_t) /* types */;
  if (writes_stresses()) bytes += array(6 * doubles) + array(doubles);
  return bytes;
}

}  // namespace flexbody::runtime
