#include "flexbody/preprocess/interfaces.hpp"

#include "../linalg/skew.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <fmt/ranges.h>
#include <stdexcept>
#include <type_traits>

namespace flexbody::preprocess {
namespace {

using detail::skew;

double default_tolerance(double tolerance, const RowMatrixX3d& nodes) {
  if (tolerance > 0.0) return tolerance;
  return kDefaultSelectorTolerance * (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm();
}

// Which nodes a selector takes (every node is tested; only surface nodes matter to the caller).
std::vector<char> selected(const std::string& name, const Selector& selector, const RowMatrixX3d& nodes) {
  std::vector<char> take(static_cast<std::size_t>(nodes.rows()), 0);
  auto unit = [&name](const Eigen::Vector3d& v, const char* what) {
    if (!(v.norm() > 0.0) || !v.allFinite())
      throw std::invalid_argument(fmt::format("{}: the {} must be a non-zero vector", name, what));
    return Eigen::Vector3d(v.normalized());
  };
  if (const auto* plane = std::get_if<PlaneSelector>(&selector)) {
    const Eigen::Vector3d n = unit(plane->normal, "plane normal");
    const double tol = default_tolerance(plane->tolerance, nodes);
    for (Eigen::Index i = 0; i < nodes.rows(); ++i)
      take[i] = std::abs((nodes.row(i).transpose() - plane->point).dot(n)) <= tol;
  } else if (const auto* cylinder = std::get_if<CylinderSelector>(&selector)) {
    const Eigen::Vector3d axis = unit(cylinder->direction, "cylinder direction");
    if (!(cylinder->radius > 0.0))
      throw std::invalid_argument(fmt::format("{}: the cylinder radius must be positive, got {}", name,
                                              cylinder->radius));
    const double tol = default_tolerance(cylinder->tolerance, nodes);
    for (Eigen::Index i = 0; i < nodes.rows(); ++i) {
      const Eigen::Vector3d d = nodes.row(i).transpose() - cylinder->point;
      take[i] = std::abs((d - d.dot(axis) * axis).norm() - cylinder->radius) <= tol;
    }
  } else if (const auto* box_selector = std::get_if<BoxSelector>(&selector)) {
    const auto& box = *box_selector;
    if (!(box.min.array() <= box.max.array()).all())
      throw std::invalid_argument(fmt::format("{}: the box min must not exceed its max", name));
    for (Eigen::Index i = 0; i < nodes.rows(); ++i)
      take[i] = (nodes.row(i).transpose().array() >= box.min.array()).all() &&
                (nodes.row(i).transpose().array() <= box.max.array()).all();
  }
  return take;
}

}  // namespace

Selector scaled(const Selector& selector, double factor) {
  return std::visit(
      [factor](auto s) -> Selector {
        using T = decltype(s);
        if constexpr (std::is_same_v<T, PlaneSelector>) {
          s.point *= factor;
          s.tolerance *= factor;
        } else if constexpr (std::is_same_v<T, CylinderSelector>) {
          s.point *= factor;
          s.radius *= factor;
          s.tolerance *= factor;
        } else if constexpr (std::is_same_v<T, BoxSelector>) {
          s.min *= factor;
          s.max *= factor;
        }  // surface tags and groups have no lengths
        return s;
      },
      selector);
}

namespace {

// The CAD surfaces a tag or group selector names.
std::vector<const CadSurface*> named_surfaces(const std::string& name, const Selector& selector,
                                              const std::vector<CadSurface>& surfaces) {
  std::vector<const CadSurface*> chosen;
  if (const auto* by_tag = std::get_if<SurfaceSelector>(&selector)) {
    for (const int tag : by_tag->tags) {
      const auto it = std::find_if(surfaces.begin(), surfaces.end(), [tag](const CadSurface& s) { return s.tag == tag; });
      if (it == surfaces.end()) {
        std::vector<int> known;
        for (const CadSurface& s : surfaces) known.push_back(s.tag);
        throw std::invalid_argument(fmt::format("{}: the part has no surface {} (surfaces: {}; see fbprep "
                                                "list-surfaces)", name, tag, known.empty() ? "none" : fmt::format("{}", fmt::join(known, ", "))));
      }
      chosen.push_back(&*it);
    }
  } else {
    const std::string& group = std::get<GroupSelector>(selector).name;
    std::set<std::string> known;
    for (const CadSurface& s : surfaces) {
      known.insert(s.groups.begin(), s.groups.end());
      if (std::find(s.groups.begin(), s.groups.end(), group) != s.groups.end()) chosen.push_back(&s);
    }
    if (chosen.empty())
      throw std::invalid_argument(fmt::format("{}: the part has no surface group '{}' (groups: {})", name,
                                              group, known.empty() ? "none" : fmt::format("{}", fmt::join(known, ", "))));
  }
  return chosen;
}

}  // namespace

SurfacePatch select_surface_patch(const std::string& label, const Selector& selector, const RowMatrixX3d& nodes,
                                  const RowMatrixX3i& surface_triangles, const std::vector<CadSurface>& surfaces) {
  std::map<int, double> area_share;  // node -> a third of its selected triangles' area
  auto add = [&](const auto& tri) {
    const Eigen::Vector3d a = nodes.row(tri(0)), b = nodes.row(tri(1)), c = nodes.row(tri(2));
    const double third = (b - a).cross(c - a).norm() / 6.0;
    for (int k = 0; k < 3; ++k) area_share[tri(k)] += third;
  };
  std::vector<char> take;
  if (std::holds_alternative<SurfaceSelector>(selector) || std::holds_alternative<GroupSelector>(selector)) {
    for (const CadSurface* surface : named_surfaces(label, selector, surfaces))
      for (Eigen::Index t = 0; t < surface->triangles.rows(); ++t) add(surface->triangles.row(t));
  } else {
    take = selected(label, selector, nodes);
    for (Eigen::Index t = 0; t < surface_triangles.rows(); ++t) {
      const auto tri = surface_triangles.row(t);
      if (take[tri(0)] && take[tri(1)] && take[tri(2)]) add(tri);
    }
  }
  if (area_share.empty()) {
    const auto count = std::count(take.begin(), take.end(), char{1});
    throw std::invalid_argument(
        count == 0 ? fmt::format("{}: the selector takes no node of the part", label)
                   : fmt::format("{}: the selector takes {} nodes but no whole surface triangle (it must "
                                 "select a surface patch, not a line or single nodes)", label, count));
  }
  double total = 0.0;
  for (const auto& [node, area] : area_share) total += area;
  SurfacePatch patch;
  patch.nodes.resize(static_cast<Eigen::Index>(area_share.size()));
  patch.weights.resize(patch.nodes.size());
  Eigen::Index k = 0;
  for (const auto& [node, area] : area_share) {
    patch.nodes(k) = node;
    patch.weights(k++) = area / total;
  }
  return patch;
}

format::Interface interface_marker(const std::string& name, const std::string& coupling, const SurfacePatch& patch,
                                   const RowMatrixX3d& body_nodes, const Eigen::MatrixXd& fields) {
  format::Interface marker;
  marker.name = name;
  marker.coupling = coupling;
  marker.nodes = patch.nodes;
  marker.weights = patch.weights;
  const Eigen::Index n_f = fields.cols();
  marker.y_row = Eigen::VectorXd::Zero(4 + n_f);
  for (Eigen::Index j = 0; j < patch.nodes.size(); ++j) {
    const double w = patch.weights(j);
    const Eigen::Index i = patch.nodes(j);
    marker.y_row(0) += w;
    marker.y_row.segment<3>(1) += w * body_nodes.row(i).transpose();
    marker.y_row.tail(n_f) += w * fields.row(i).transpose();
  }
  marker.reference_point = marker.y_row.segment<3>(1);
  // Weighted least-squares rigid fit of the displacements u_i = Σ_f υ'_f(i) ξ̄_f about the reference
  // point: H θ̄ = Σ_i w_i d_i × u_i with H = Σ_i w_i (|d_i|² I − d_i d_iᵀ), d_i = X̄_i − X̄_c.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd moments = Eigen::MatrixXd::Zero(3, 3 * n_f);  // Σ_i w_i υ'_f(i) skew(d_i), per field f
  for (Eigen::Index j = 0; j < patch.nodes.size(); ++j) {
    const double w = patch.weights(j);
    const Eigen::Index i = patch.nodes(j);
    const Eigen::Vector3d d = body_nodes.row(i).transpose() - marker.reference_point;
    h += w * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    const Eigen::Matrix3d s = skew(d);
    for (Eigen::Index f = 0; f < n_f; ++f) moments.middleCols<3>(3 * f) += (w * fields(i, f)) * s;
  }
  // The smallest principal value of H is zero exactly when the nodes lie on one line.
  const Eigen::Vector3d principal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(h).eigenvalues();
  if (!(principal(0) > 1e-10 * principal(2)))
    throw std::invalid_argument(fmt::format("interface '{}': its nodes lie on a line, so their rotation about it is "
                                            "undefined; select a surface patch", name));
  marker.rotation = h.ldlt().solve(moments);
  return marker;
}

std::vector<SelectedInterface> select_interfaces(const std::vector<InterfaceRequest>& requests,
                                                const RowMatrixX3d& input_nodes, const RowMatrixX3i& surface_triangles,
                                                const std::vector<CadSurface>& surfaces) {
  std::vector<SelectedInterface> selected_interfaces;
  std::map<int, std::string> owner;  // node -> interface
  std::set<std::string> names;
  for (const InterfaceRequest& request : requests) {
    if (request.name.empty() || request.name.find_first_of("/,") != std::string::npos || request.name == "order")
      throw std::invalid_argument(fmt::format("{} name '{}' is not allowed (non-empty, no '/' or ',')", request.kind,
                                              request.name));
    const std::string label = fmt::format("{} '{}'", request.kind, request.name);
    if (!names.insert(request.name).second) throw std::invalid_argument(fmt::format("{} is defined twice", label));
    if (request.coupling != "rbe2" && request.coupling != "rbe3")
      throw std::invalid_argument(
          fmt::format("{}: coupling '{}' is unknown; use rbe2 or rbe3", label, request.coupling));
    SurfacePatch patch = select_surface_patch(label, request.select, input_nodes, surface_triangles, surfaces);
    for (Eigen::Index j = 0; j < patch.nodes.size(); ++j) {
      const auto [it, fresh] = owner.emplace(patch.nodes(j), label);
      if (!fresh)
        throw std::invalid_argument(fmt::format(
            "{} and {} share node {} (at [{:.6g}, {:.6g}, {:.6g}] m): interfaces and load points must not overlap",
            it->second, label, patch.nodes(j), input_nodes(patch.nodes(j), 0), input_nodes(patch.nodes(j), 1),
            input_nodes(patch.nodes(j), 2)));
    }
    selected_interfaces.push_back({request.name, request.coupling, std::move(patch)});
  }
  return selected_interfaces;
}

Eigen::Vector3d patch_centroid(const SurfacePatch& patch, const RowMatrixX3d& nodes) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (Eigen::Index j = 0; j < patch.nodes.size(); ++j) centroid += patch.weights(j) * nodes.row(patch.nodes(j)).transpose();
  return centroid;
}

std::vector<format::Interface> build_interfaces(const std::vector<InterfaceRequest>& requests,
                                                const RowMatrixX3d& body_nodes,
                                                const Eigen::Vector3d& center_of_mass_input,
                                                const RowMatrixX3i& surface_triangles, const Eigen::MatrixXd& fields,
                                                const std::vector<CadSurface>& surfaces) {
  const RowMatrixX3d input_nodes = body_nodes.rowwise() + center_of_mass_input.transpose();
  std::vector<format::Interface> markers;
  for (const SelectedInterface& s : select_interfaces(requests, input_nodes, surface_triangles, surfaces))
    markers.push_back(interface_marker(s.name, s.coupling, s.patch, body_nodes, fields));
  return markers;
}

}  // namespace flexbody::preprocess
