#include "flexbody/runtime/assembly.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

// The rigid coordinates of body b: τ and a (12) of a GCMS body, τ and p (7) of a floating-frame one.
Eigen::Index rigid_count(const BodyModel& model) { return model.floating() ? 7 : 12; }

Eigen::Matrix3d orientation_at(const BodyModel& model, const Eigen::VectorXd& q, Eigen::Index o) {
  return model.floating() ? euler_rotation(q.segment<4>(o + 3).normalized()) : Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix3d>(q.data() + o + 3));
}

// The largest distance of a point of the body from its centre of mass [m].
double body_radius(const BodyModel& model) {
  if (model.nodes.rows() > 0) return model.nodes.rowwise().norm().maxCoeff();
  return 0.5 * body_size(model);
}

}  // namespace

double body_size(const BodyModel& model) {
  const format::RowMatrixX3d& nodes = model.nodes;
  if (nodes.rows() > 0) return (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm();
  const double trace = model.g_border(1, 1) + model.g_border(2, 2) + model.g_border(3, 3);
  return 2.0 * std::sqrt(3.0 * std::max(trace, 0.0) / model.mass);  // a cube's diagonal for its radius of gyration
}

int AssemblyReport::most_moved() const {
  if (moves.empty()) return -1;
  return static_cast<int>(std::max_element(moves.begin(), moves.end()) - moves.begin());
}

AssemblyReport assemble(System& system, const AssemblyOptions& options) {
  if (!(options.tolerance > 0.0) || options.max_iterations < 1)
    throw std::invalid_argument("assembly: tolerance > 0 and max_iterations >= 1 are required");
  const int n_b = system.body_count();
  const Eigen::VectorXd q0 = system.initial_coordinates();
  Eigen::VectorXd q = q0;
  // The unknowns (every body's rigid coordinates) and the rows (the joints', and each body's rigidity: 6
  // orthogonality rows, or the Euler parameters' normalisation); the Tisserand rows concern ξ, which stays.
  std::vector<Eigen::Index> column_of(static_cast<std::size_t>(q.size()), -1), row_of(static_cast<std::size_t>(system.constraint_count()), -1);
  Eigen::Index n_r = 0, m_r = 0;
  for (int b = 0; b < n_b; ++b) {
    const BodyModel& model = system.model(b);
    for (Eigen::Index i = 0; i < rigid_count(model); ++i) column_of[static_cast<std::size_t>(system.offset(b) + i)] = n_r++;
    for (Eigen::Index i = 0; i < (model.floating() ? 1 : 6); ++i) row_of[static_cast<std::size_t>(system.reference_row(b) + i)] = m_r++;
  }
  for (Eigen::Index k = system.joint_row(0); k < system.constraint_count(); ++k) row_of[static_cast<std::size_t>(k)] = m_r++;
  // Converged when the rows are at the rounding of the positions they compare.
  double extent = 1.0;
  for (int b = 0; b < n_b; ++b) extent = std::max(extent, q0.segment<3>(system.offset(b)).norm() + body_size(system.model(b)));
  for (const Joint& j : system.joints())
    for (const Marker* m : {&j.first, &j.second})
      if (m->body == kGround) extent = std::max(extent, m->ground_point.norm());
  const double converged = 64.0 * std::numeric_limits<double>::epsilon() * extent;
  AssemblyReport report;
  report.moves.assign(static_cast<std::size_t>(n_b), 0.0);
  const Eigen::VectorXd phi0 = system.constraints(0.0, q0);
  report.largest_gap = system.joints().empty() ? 0.0 : phi0.tail(system.constraint_count() - system.joint_row(0)).cwiseAbs().maxCoeff();
  // The joint whose gap is largest against its bodies' sizes: the one a refusal names.
  if (system.joints().empty()) {  // only the bodies' own rows: a body whose orientation is not a rotation
    const Eigen::VectorXd phi = system.constraints(0.0, q0);
    Eigen::Index row = 0;
    if (phi.size() > 0 && phi.cwiseAbs().maxCoeff(&row) > 1e-8)
      throw std::invalid_argument("assembly: " + system.constraint_name(row) + " is violated by " + std::to_string(phi(row)));
    return report;
  }
  auto smaller_size = [&](const Joint& j) {  // of the joint's bodies [m]
    double size = std::numeric_limits<double>::infinity();
    for (const Marker* m : {&j.first, &j.second})
      if (m->body != kGround) size = std::min(size, body_size(system.model(m->body)));
    return size;
  };
  auto worst_joint = [&]() -> std::size_t {
    std::size_t worst = 0;
    double worst_share = -1.0;
    for (std::size_t k = 0; k < system.joints().size(); ++k) {
      const Joint& j = system.joints()[k];
      if (j.rows() == 0) continue;  // every row removed as redundant
      const double gap = phi0.segment(system.joint_row(k), j.rows()).cwiseAbs().maxCoeff(), size = smaller_size(j);
      if (gap / size > worst_share) worst_share = gap / size, worst = k;
    }
    return worst;
  };
  bool done = false;
  for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
    const Eigen::VectorXd phi = system.constraints(0.0, q);
    double largest = 0.0;
    for (Eigen::Index k = 0; k < phi.size(); ++k)
      if (row_of[static_cast<std::size_t>(k)] >= 0) largest = std::max(largest, std::abs(phi(k)));
    if (largest <= converged) {
      done = true;
      break;
    }
    if (iteration == options.max_iterations) break;
    ++report.iterations;
    Eigen::SparseMatrix<double> jacobian;
    system.sparse_constraint_jacobian(0.0, q, jacobian);
    const Eigen::SparseMatrix<double> mass = system.sparse_mass_matrix(q);
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index c = 0; c < mass.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(mass, c); it; ++it) {
        const Eigen::Index r = column_of[static_cast<std::size_t>(it.row())], k = column_of[static_cast<std::size_t>(it.col())];
        if (r >= 0 && k >= 0) entries.emplace_back(r, k, it.value());
      }
    for (Eigen::Index c = 0; c < jacobian.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(jacobian, c); it; ++it) {
        const Eigen::Index r = row_of[static_cast<std::size_t>(it.row())], k = column_of[static_cast<std::size_t>(it.col())];
        if (r >= 0 && k >= 0 && it.value() != 0.0) {
          entries.emplace_back(n_r + r, k, it.value());
          entries.emplace_back(k, n_r + r, it.value());
        }
      }
    Eigen::SparseMatrix<double> kkt(n_r + m_r, n_r + m_r);
    kkt.setFromTriplets(entries.begin(), entries.end());
    kkt.makeCompressed();
    Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu(kkt);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n_r + m_r);
    for (Eigen::Index k = 0; k < phi.size(); ++k)
      if (row_of[static_cast<std::size_t>(k)] >= 0) rhs(n_r + row_of[static_cast<std::size_t>(k)]) = -phi(k);
    const Eigen::VectorXd x = lu.info() == Eigen::Success ? Eigen::VectorXd(lu.solve(rhs)) : Eigen::VectorXd();
    if (!x.allFinite() || x.size() == 0) {
      const std::size_t k = worst_joint();
      const Joint& j = system.joints()[k];
      throw AssemblyError("assembly: joint '" + j.name + "' cannot be closed: the joints' rows are dependent "
                                  "where the bodies are (a redundant joint or a singular position)", k);
    }
    for (Eigen::Index i = 0; i < q.size(); ++i)
      if (column_of[static_cast<std::size_t>(i)] >= 0) q(i) += x(column_of[static_cast<std::size_t>(i)]);
  }
  if (!done) {
    const std::size_t k = worst_joint();
    const Joint& j = system.joints()[k];
    std::ostringstream why;
    why << "assembly: joint '" << j.name << "' cannot be closed in " << options.max_iterations << " steps: its markers "
        << j.first.name << " and " << j.second.name << " are too far apart for the mechanism to reach";
    throw AssemblyError(why.str(), k);
  }
  for (int b = 0; b < n_b; ++b) {  // a GCMS body's ξ (global axes) turns with it, so that its deformation ξ̄ = Aᵀ ξ stays
    const BodyModel& model = system.model(b);
    if (model.floating() || model.rigid()) continue;
    const Eigen::Index o = system.offset(b);
    const Eigen::Matrix3d turn = orientation_at(model, q, o) * orientation_at(model, q0, o).transpose();
    for (Eigen::Index f = 0; f < model.field_count(); ++f) q.segment<3>(o + 12 + 3 * f) = turn * q0.segment<3>(o + 12 + 3 * f);
  }
  for (int b = 0; b < n_b; ++b) {  // the largest displacement of a point: |Δτ| + |ΔA| times the body's radius
    const BodyModel& model = system.model(b);
    const Eigen::Index o = system.offset(b);
    const double turn = (orientation_at(model, q, o) - orientation_at(model, q0, o)).norm();
    report.moves[static_cast<std::size_t>(b)] = (q - q0).segment<3>(o).norm() + turn * body_radius(model);
    if (report.moves[static_cast<std::size_t>(b)] > options.tolerance * body_size(model)) {
      const std::size_t k = worst_joint();
      const Joint& j = system.joints()[k];
      std::ostringstream why;
      why << "joint '" << j.name << "': its markers " << j.first.name << " and " << j.second.name << " are "
          << (j.rows() > 0 ? phi0.segment(system.joint_row(k), j.rows()).cwiseAbs().maxCoeff() : 0.0)
          << " m apart; closing them moves body '" << system.body_name(b) << "' by " << report.moves[static_cast<std::size_t>(b)]
          << " m, more than the assembly tolerance (" << 100.0 * options.tolerance << " % of its size, "
          << body_size(model) << " m): the scene must start nearly assembled";
      throw AssemblyError(why.str(), k);
    }
  }
  // Rows left out as redundant (System::remove_redundant_constraints) are not closed by the assembly: they hold
  // only if the loop closes. One off by more than the tolerance (a length against the smaller body's size, a
  // direction row as it is, about an angle) is an inconsistent redundant constraint: the parts do not fit.
  for (std::size_t k = 0; k < system.joints().size(); ++k) {
    const Joint& j = system.joints()[k];
    if (j.removed == 0) continue;
    const Eigen::VectorXd q1 = system.body_coordinates(q, j.first.body), q2 = system.body_coordinates(q, j.second.body);
    const Eigen::VectorXd all = joint_type_residuals(j, 0.0, q1, q2);
    for (int row = 0; row < j.type_rows(); ++row) {
      if (!((j.removed >> row) & 1U)) continue;
      const bool length = row < j.length_rows();
      if (std::abs(all(row)) <= options.tolerance * (length ? smaller_size(j) : 1.0)) continue;
      std::ostringstream why;
      why << "joint '" << j.name << "': its redundant row (" << joint_row_meaning(j, row, q1, q2) << ") is off by "
          << std::abs(all(row)) << (length ? " m" : "") << " once the other joints are closed, more than the assembly "
          << "tolerance: the parts do not fit (an inconsistent redundant constraint)";
      throw AssemblyError(why.str(), k);
    }
  }
  system.set_initial_coordinates(q);
  return report;
}

}  // namespace flexbody::runtime
