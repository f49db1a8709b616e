#include "flexbody/runtime/initial_assembly.hpp"

#include "../body/body_measures.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/ffrf_model.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace flexbody::runtime {
namespace {

// How much cheaper a rigid move is than a deformation of the same size, where the assembly may deform bodies: the
// metric is M + K_e / (ε ω₁²), so a move along a body's first mode costs 1/ε times its kinetic-energy norm. The
// misfit a closed loop's rigid moves cannot take is then taken by the least strain energy, and a part of order ε of
// any other gap (5 µm x 1e-6: picometres).
constexpr double kRigidPreference = 1e-6;

// The rigid coordinates of body b: τ and a (12) of a GCMS body, τ and p (7) of a floating-frame one.
Eigen::Index rigid_count(const BodyModel& model) { return model.floating() ? 7 : 12; }

Eigen::Matrix3d orientation_at(const BodyModel& model, const Eigen::VectorXd& q, Eigen::Index o) {
  return model.floating() ? euler_rotation(q.segment<4>(o + 3).normalized())
                          : Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix3d>(q.data() + o + 3));
}

// The largest distance of a point of the body from its centre of mass [m].
double body_radius(const BodyModel& model) {
  if (model.nodes.rows() > 0) return model.nodes.rowwise().norm().maxCoeff();
  return 0.5 * body_size(model);
}

// The squared circular frequency [1/s²] of the body's first mode, which scales its stiffness in the assembly's
// metric, or 0 for a body the assembly keeps rigid: rigid bodies, and the full-order reference (its K̄ and mesh are
// too large to enter a dense metric, and it has no first frequency to scale it by).
double deformation_scale(const BodyModel& model) {
  if (model.floating()) {
    const Eigen::VectorXd diagonal = model.floating_frame->modal_stiffness.diagonal();
    return diagonal.size() > 0 ? diagonal.minCoeff() : 0.0;
  }
  if (model.rigid() || model.sparse || model.frequencies_hz.size() == 0) return 0.0;
  return std::pow(2.0 * M_PI * model.frequencies_hz(0), 2);  // the basis's first mode, as K_ff's smallest entry
}

// The bodies that lie on a closed loop of joints (ground counts as one node): those joined by a joint that is not a
// bridge of the body graph (Tarjan's low-link test, iterative so that a chain of thousands of links needs no deep
// recursion; two joints between the same two bodies make a loop too). Only a loop can ask a body to deform.
std::vector<bool> bodies_on_loops(const System& system) {
  const int n_b = system.body_count(), nodes = n_b + 1;  // node n_b is ground
  struct Edge {
    int to;
    std::size_t id;
  };
  std::vector<std::vector<Edge>> adjacent(static_cast<std::size_t>(nodes));
  std::vector<std::pair<int, int>> ends;
  for (const Joint& j : system.joints()) {
    if (j.rows() == 0) continue;  // every row removed as redundant: it joins nothing
    const int a = j.first.body == kGround ? n_b : j.first.body, b = j.second.body == kGround ? n_b : j.second.body;
    if (a == b) continue;
    adjacent[static_cast<std::size_t>(a)].push_back({b, ends.size()});
    adjacent[static_cast<std::size_t>(b)].push_back({a, ends.size()});
    ends.emplace_back(a, b);
  }
  std::vector<int> order(static_cast<std::size_t>(nodes), -1), low(static_cast<std::size_t>(nodes), 0);
  std::vector<bool> bridge(ends.size(), false);
  struct Frame {
    int node;
    std::size_t via;  // the edge it was entered by (ends.size() for a root)
    std::size_t next;
  };
  int counter = 0;
  for (int root = 0; root < nodes; ++root) {
    if (order[static_cast<std::size_t>(root)] >= 0) continue;
    std::vector<Frame> stack{{root, ends.size(), 0}};
    order[static_cast<std::size_t>(root)] = low[static_cast<std::size_t>(root)] = counter++;
    while (!stack.empty()) {
      Frame& f = stack.back();
      const auto u = static_cast<std::size_t>(f.node);
      if (f.next < adjacent[u].size()) {
        const Edge e = adjacent[u][f.next++];
        if (e.id == f.via) continue;  // the edge back to the parent (a parallel edge has another id)
        const auto v = static_cast<std::size_t>(e.to);
        if (order[v] < 0) {
          order[v] = low[v] = counter++;
          stack.push_back({e.to, e.id, 0});
        } else {
          low[u] = std::min(low[u], order[v]);
        }
      } else {
        const Frame done = f;
        stack.pop_back();
        if (!stack.empty()) {
          const auto parent = static_cast<std::size_t>(stack.back().node), child = static_cast<std::size_t>(done.node);
          low[parent] = std::min(low[parent], low[child]);
          if (low[child] > order[parent]) bridge[done.via] = true;
        }
      }
    }
  }
  std::vector<bool> on_loop(static_cast<std::size_t>(n_b), false);
  for (std::size_t k = 0; k < ends.size(); ++k) {
    if (bridge[k]) continue;
    for (const int node : {ends[k].first, ends[k].second})
      if (node < n_b) on_loop[static_cast<std::size_t>(node)] = true;
  }
  return on_loop;
}

// The unknowns of one Gauss-Newton solve: which coordinates move and which constraint rows hold them, and per body
// the weight of its stiffness in the metric (0: it moves rigidly).
struct Unknowns {
  std::vector<Eigen::Index> column_of, row_of;
  std::vector<bool> checked;  ///< rows whose residual decides convergence (the Tisserand rows are solved, not checked)
  std::vector<double> stiffness_weight;
  Eigen::Index columns = 0, rows = 0;
  [[nodiscard]] bool deforms() const {
    return std::any_of(stiffness_weight.begin(), stiffness_weight.end(), [](double w) { return w > 0.0; });
  }
};

// Every body's rigid coordinates with its rigidity rows (6 orthogonality rows, or the Euler parameters'
// normalisation), and every joint row; also the deformation (ξ, η) of the bodies marked `deformable` that have a
// deformation_scale, with their Tisserand rows.
Unknowns choose_unknowns(const System& system, const std::vector<bool>& deformable) {
  Unknowns u;
  const auto n = static_cast<std::size_t>(system.coordinate_count()),
             m = static_cast<std::size_t>(system.constraint_count());
  u.column_of.assign(n, -1);
  u.row_of.assign(m, -1);
  u.checked.assign(m, false);
  u.stiffness_weight.assign(static_cast<std::size_t>(system.body_count()), 0.0);
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    const double scale = deformable[static_cast<std::size_t>(b)] ? deformation_scale(model) : 0.0;
    if (scale > 0.0) u.stiffness_weight[static_cast<std::size_t>(b)] = 1.0 / (kRigidPreference * scale);
    const Eigen::Index moving = scale > 0.0 ? model.coordinate_count() : rigid_count(model);
    for (Eigen::Index i = 0; i < moving; ++i) u.column_of[static_cast<std::size_t>(system.offset(b) + i)] = u.columns++;
    const Eigen::Index rigidity = model.floating() ? 1 : 6;
    const Eigen::Index rows = scale > 0.0 ? system.reference_row(b + 1) - system.reference_row(b) : rigidity;
    for (Eigen::Index i = 0; i < rows; ++i) {
      const auto k = static_cast<std::size_t>(system.reference_row(b) + i);
      u.row_of[k] = u.rows++;
      u.checked[k] = i < rigidity;
    }
  }
  for (Eigen::Index k = system.joint_row(0); k < system.constraint_count(); ++k) {
    u.row_of[static_cast<std::size_t>(k)] = u.rows++;
    u.checked[static_cast<std::size_t>(k)] = true;
  }
  return u;
}

// The metric's entries over the unknowns: M(q), plus each deforming body's strain-energy Hessian ∂²U/∂ξ² = Â K̂ Âᵀ
// (Eq. 96; GCMS) or K_ff (floating frame), times its weight.
void add_metric(const System& system, const Unknowns& u, const Eigen::VectorXd& q,
                std::vector<Eigen::Triplet<double>>& entries) {
  const Eigen::SparseMatrix<double> mass = system.sparse_mass_matrix(q);
  for (Eigen::Index c = 0; c < mass.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(mass, c); it; ++it) {
      const Eigen::Index r = u.column_of[static_cast<std::size_t>(it.row())],
                         k = u.column_of[static_cast<std::size_t>(it.col())];
      if (r >= 0 && k >= 0) entries.emplace_back(r, k, it.value());
    }
  for (int b = 0; b < system.body_count(); ++b) {
    const double weight = u.stiffness_weight[static_cast<std::size_t>(b)];
    if (weight == 0.0) continue;
    const BodyModel& model = system.model(b);
    const Eigen::Index o = system.offset(b);
    Eigen::MatrixXd hessian;
    Eigen::Index first = 0;
    if (model.floating()) {
      hessian = model.floating_frame->modal_stiffness;
      first = 7;
    } else {
      const Eigen::VectorXd q_b = q.segment(o, model.coordinate_count());
      hessian = body_elastic_tangent(model, orientation_at(model, q, o), q_b.tail(q_b.size() - 12), true).xi_xi;
      first = 12;
    }
    const Eigen::Index start = u.column_of[static_cast<std::size_t>(o + first)];
    for (Eigen::Index c = 0; c < hessian.cols(); ++c)
      for (Eigen::Index r = 0; r < hessian.rows(); ++r)
        if (hessian(r, c) != 0.0) entries.emplace_back(start + r, start + c, weight * hessian(r, c));
  }
}

// The coefficients of Y = [1, X̄, Ῡ'] ((4 + n_f) x 3) of body b's deformation at q: ξ̄ = Âᵀ ξ in rows 4.. of a GCMS
// body; Σ_m η_m W_m of a floating-frame one (whose rows 0..3 carry the interface frame's rigid part).
Eigen::MatrixX3d deformation_coefficients(const System& system, int b, const Eigen::VectorXd& q) {
  const BodyModel& model = system.model(b);
  const Eigen::Index o = system.offset(b), n_f = model.field_count();
  Eigen::MatrixX3d c = Eigen::MatrixX3d::Zero(4 + n_f, 3);
  if (model.floating()) {
    const FfrfModel& ff = *model.floating_frame;
    for (Eigen::Index k = 0; k < ff.modes; ++k) c += q(o + 7 + k) * ff.shapes.middleCols<3>(3 * k);
  } else {
    const Eigen::Matrix3d a = orientation_at(model, q, o);
    for (Eigen::Index f = 0; f < n_f; ++f) c.row(4 + f) = (a.transpose() * q.segment<3>(o + 12 + 3 * f)).transpose();
  }
  return c;
}

// The largest displacement of a node of body b by the change of deformation `change` (deformation_coefficients'
// difference) [m]; for a body without a mesh, the root mean square over its mass.
double largest_deformation(const BodyModel& model, const Eigen::MatrixX3d& change) {
  if (model.nodes.rows() == 0 || model.fields.rows() != model.nodes.rows()) {
    const Eigen::MatrixXd& g = model.mass_matrix;
    return g.size() > 0 ? std::sqrt(std::max(0.0, (change.transpose() * g * change).trace() / model.mass)) : 0.0;
  }
  double largest = 0.0;
  for (Eigen::Index i = 0; i < model.nodes.rows(); ++i) {
    const Eigen::RowVector3d u = change.row(0) + model.nodes.row(i) * change.middleRows<3>(1) +
                                 model.fields.row(i) * change.bottomRows(change.rows() - 4);
    largest = std::max(largest, u.norm());
  }
  return largest;
}

enum class Outcome { converged, singular, not_converged };

// Gauss-Newton on the linearised rows, each step the correction of least metric norm (initial_assembly.hpp), until the
// checked rows are at `converged` [m] (the rounding of the positions they compare).
Outcome gauss_newton(const System& system, const Unknowns& u, const InitialAssemblyOptions& options, double converged,
                     Eigen::VectorXd& q, int& iterations) {
  for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
    const Eigen::VectorXd phi = system.constraints(0.0, q);
    double largest = 0.0;
    for (Eigen::Index k = 0; k < phi.size(); ++k)
      if (u.checked[static_cast<std::size_t>(k)]) largest = std::max(largest, std::abs(phi(k)));
    if (largest <= converged) return Outcome::converged;
    if (iteration == options.max_iterations) break;
    ++iterations;
    Eigen::SparseMatrix<double> jacobian;
    system.sparse_constraint_jacobian(0.0, q, jacobian);
    std::vector<Eigen::Triplet<double>> entries;
    add_metric(system, u, q, entries);
    for (Eigen::Index c = 0; c < jacobian.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(jacobian, c); it; ++it) {
        const Eigen::Index r = u.row_of[static_cast<std::size_t>(it.row())],
                           k = u.column_of[static_cast<std::size_t>(it.col())];
        if (r >= 0 && k >= 0 && it.value() != 0.0) {
          entries.emplace_back(u.columns + r, k, it.value());
          entries.emplace_back(k, u.columns + r, it.value());
        }
      }
    Eigen::SparseMatrix<double> kkt(u.columns + u.rows, u.columns + u.rows);
    kkt.setFromTriplets(entries.begin(), entries.end());
    kkt.makeCompressed();
    Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu(kkt);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(u.columns + u.rows);
    for (Eigen::Index k = 0; k < phi.size(); ++k)
      if (u.row_of[static_cast<std::size_t>(k)] >= 0) rhs(u.columns + u.row_of[static_cast<std::size_t>(k)]) = -phi(k);
    const Eigen::VectorXd x = lu.info() == Eigen::Success ? Eigen::VectorXd(lu.solve(rhs)) : Eigen::VectorXd();
    if (x.size() == 0 || !x.allFinite()) return Outcome::singular;
    for (Eigen::Index i = 0; i < q.size(); ++i)
      if (u.column_of[static_cast<std::size_t>(i)] >= 0) q(i) += x(u.column_of[static_cast<std::size_t>(i)]);
  }
  return Outcome::not_converged;
}

}  // namespace

double body_size(const BodyModel& model) {
  if (model.nodes.rows() > 0) return detail::mesh_diagonal(model);
  const double trace = model.g_border(1, 1) + model.g_border(2, 2) + model.g_border(3, 3);
  return 2.0 * std::sqrt(3.0 * std::max(trace, 0.0) / model.mass);  // a cube's diagonal for its radius of gyration
}

int InitialAssemblyReport::most_moved() const {
  if (moves.empty()) return -1;
  return static_cast<int>(std::max_element(moves.begin(), moves.end()) - moves.begin());
}

InitialAssemblyReport initial_assembly(System& system, const InitialAssemblyOptions& options) {
  if (!(options.tolerance > 0.0) || options.max_iterations < 1)
    throw std::invalid_argument("assembly: tolerance > 0 and max_iterations >= 1 are required");
  const int n_b = system.body_count();
  const Eigen::VectorXd q0 = system.initial_coordinates();
  Eigen::VectorXd q = q0;
  // Converged when the rows are at the rounding of the positions they compare.
  double extent = 1.0;
  for (int b = 0; b < n_b; ++b)
    extent = std::max(extent, q0.segment<3>(system.offset(b)).norm() + body_size(system.model(b)));
  for (const Joint& j : system.joints())
    for (const Marker* m : {&j.first, &j.second})
      if (m->body == kGround) extent = std::max(extent, m->ground_point.norm());
  const double converged = 64.0 * std::numeric_limits<double>::epsilon() * extent;
  InitialAssemblyReport report;
  report.moves.assign(static_cast<std::size_t>(n_b), 0.0);
  report.deformations.assign(static_cast<std::size_t>(n_b), 0.0);
  const Eigen::VectorXd phi0 = system.constraints(0.0, q0);
  report.largest_gap =
      system.joints().empty() ? 0.0 : phi0.tail(system.constraint_count() - system.joint_row(0)).cwiseAbs().maxCoeff();
  // The joint whose gap is largest against its bodies' sizes: the one a refusal names.
  if (system.joints().empty()) {  // only the bodies' own rows: a body whose orientation is not a rotation
    Eigen::Index row = 0;
    if (phi0.size() > 0 && phi0.cwiseAbs().maxCoeff(&row) > 1e-8)
      throw std::invalid_argument("assembly: " + system.constraint_name(row) + " is violated by " +
                                  std::to_string(phi0(row)));
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
  // A closed loop with a flexible body: its rows may be independent only through the body's deformation (the
  // redundancy check, System::remove_redundant_constraints, counts it), so the assembly may deform the flexible
  // bodies on loops too.
  const Unknowns unknowns = choose_unknowns(system, bodies_on_loops(system));
  switch (gauss_newton(system, unknowns, options, converged, q, report.iterations)) {
    case Outcome::converged:
      break;
    case Outcome::singular: {
      const std::size_t k = worst_joint();
      throw InitialAssemblyError("assembly: joint '" + system.joints()[k].name +
                                     "' cannot be closed: the joints' rows are "
                                     "dependent where the bodies are (a redundant joint or a singular position)",
                                 k);
    }
    case Outcome::not_converged: {
      const std::size_t k = worst_joint();
      const Joint& j = system.joints()[k];
      std::ostringstream why;
      why << "assembly: joint '" << j.name << "' cannot be closed in " << options.max_iterations
          << " steps: its markers " << j.first.name << " and " << j.second.name
          << " are too far apart for the mechanism to reach";
      throw InitialAssemblyError(why.str(), k);
    }
  }
  for (int b = 0; b < n_b; ++b) {  // a rigidly moved GCMS body's ξ (global axes) turns with it: its ξ̄ = Aᵀ ξ stays
    const BodyModel& model = system.model(b);
    if (model.floating() || model.rigid() || unknowns.stiffness_weight[static_cast<std::size_t>(b)] > 0.0) continue;
    const Eigen::Index o = system.offset(b);
    const Eigen::Matrix3d turn = orientation_at(model, q, o) * orientation_at(model, q0, o).transpose();
    for (Eigen::Index f = 0; f < model.field_count(); ++f)
      q.segment<3>(o + 12 + 3 * f) = turn * q0.segment<3>(o + 12 + 3 * f);
  }
  // Per body, the largest displacement of a point: |Δτ| + |ΔA| times the body's radius, plus its deformation's.
  for (int b = 0; b < n_b; ++b) {
    const BodyModel& model = system.model(b);
    const Eigen::Index o = system.offset(b);
    const auto i = static_cast<std::size_t>(b);
    if (unknowns.stiffness_weight[i] > 0.0)
      report.deformations[i] =
          largest_deformation(model, deformation_coefficients(system, b, q) - deformation_coefficients(system, b, q0));
    const double turn = (orientation_at(model, q, o) - orientation_at(model, q0, o)).norm();
    report.moves[i] = (q - q0).segment<3>(o).norm() + turn * body_radius(model) + report.deformations[i];
    if (report.moves[i] > options.tolerance * body_size(model)) {
      const std::size_t k = worst_joint();
      const Joint& j = system.joints()[k];
      std::ostringstream why;
      why << "joint '" << j.name << "': its markers " << j.first.name << " and " << j.second.name << " are "
          << (j.rows() > 0 ? phi0.segment(system.joint_row(k), j.rows()).cwiseAbs().maxCoeff() : 0.0)
          << " m apart; closing them moves body '" << system.body_name(b) << "' by " << report.moves[i]
          << " m, more than the assembly tolerance (" << 100.0 * options.tolerance << " % of its size, "
          << body_size(model) << " m): the scene must start nearly assembled";
      throw InitialAssemblyError(why.str(), k);
    }
  }
  if (unknowns.deforms()) {
    const Eigen::VectorXd rest = Eigen::VectorXd::Zero(q.size());
    report.strain_energy = std::max(0.0, system.energies(q, rest).elastic - system.energies(q0, rest).elastic);
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
      throw InitialAssemblyError(why.str(), k);
    }
  }
  system.set_initial_coordinates(q);
  return report;
}

}  // namespace flexbody::runtime
