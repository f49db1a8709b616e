#include "flexbody/preprocess/vtu_export.hpp"

#include "flexbody/format/vtk_xml.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

namespace flexbody::preprocess {
namespace {

// Stresses are computed for this many modes at a time: 6 n_n doubles each (48 MB per mode at 1M nodes).
constexpr Eigen::Index kStressModeBlock = 8;
// ParaView's SymmetricTensor order XX, YY, ZZ, XY, YZ, XZ as indices into our Voigt order xx, yy, zz, xy, xz, yz.
constexpr std::array<int, kStressComponents> kParaViewFromVoigt = {0, 1, 2, 3, 5, 4};

}  // namespace

std::string mode_array_name(int m, double frequency_hz) { return fmt::format("mode_{:02d}_{:.6g}Hz", m + 1, frequency_hz); }

std::string stress_array_name(int m, double frequency_hz) {
  return "stress_" + mode_array_name(m, frequency_hz).substr(std::string_view("mode_").size());
}

std::string mises_array_name(int m) { return fmt::format("mises_{:02d}", m + 1); }

void write_body_vtu(const format::BodyData& body, const std::filesystem::path& path) {
  const auto& mesh = body.mesh;
  const Eigen::Index n_n = mesh.nodes.rows(), n_e = mesh.tets.rows();
  format::VtuWriter out(path, n_n, n_e);
  std::vector<double> vectors(static_cast<std::size_t>(3 * n_n)), tensors(static_cast<std::size_t>(6 * n_n)),
      mises(static_cast<std::size_t>(n_n));
  const bool quadratic = mesh.element_order == 2;
  const TetMesh tet_mesh = quadratic ? TetMesh{} : TetMesh{mesh.nodes, mesh.tets};
  const Tet10Mesh tet10_mesh = quadratic ? Tet10Mesh{mesh.nodes, mesh.tets} : Tet10Mesh{};
  for (Eigen::Index first = 0; first < body.modes.count(); first += kStressModeBlock) {
    const Eigen::Index block = std::min(kStressModeBlock, body.modes.count() - first);
    Eigen::MatrixXd displacements(3 * n_n, block);  // node-interleaved columns of Ῡ
    for (Eigen::Index c = 0; c < block; ++c)
      for (Eigen::Index i = 0; i < n_n; ++i)
        for (int k = 0; k < 3; ++k) displacements(3 * i + k, c) = body.modes.upsilon(i, 3 * (first + c) + k);
    const Eigen::MatrixXd stresses = quadratic ? nodal_stresses(tet10_mesh, body.material, displacements)
                                               : nodal_stresses(tet_mesh, body.material, displacements);
    for (Eigen::Index c = 0; c < block; ++c) {
      const int m = static_cast<int>(first + c);
      const double frequency = body.modes.frequencies_hz(m);
      for (Eigen::Index i = 0; i < n_n; ++i)
        for (int k = 0; k < 3; ++k) vectors[3 * i + k] = displacements(3 * i + k, c);
      out.point_array(mode_array_name(m, frequency), 3, vectors);
      for (Eigen::Index i = 0; i < n_n; ++i) {
        const Eigen::Matrix<double, kStressComponents, 1> s = stresses.col(c).segment<kStressComponents>(6 * i);
        for (int k = 0; k < kStressComponents; ++k) tensors[6 * i + k] = s(kParaViewFromVoigt[k]);
        mises[i] = von_mises(s);
      }
      out.point_array(stress_array_name(m, frequency), 6, tensors);
      out.point_array(mises_array_name(m), 1, mises);
    }
  }
  std::vector<double> scalars(static_cast<std::size_t>(n_n));
  for (Eigen::Index f = 0; f < body.gcms.field_count(); ++f) {
    for (Eigen::Index i = 0; i < n_n; ++i) scalars[i] = body.gcms.fields(i, f);
    out.point_array(fmt::format("field_{:03d}", f + 1), 1, scalars);
  }
  std::vector<std::int32_t> owner(static_cast<std::size_t>(n_n), 0);
  for (std::size_t k = 0; k < body.interfaces.size(); ++k)
    for (Eigen::Index j = 0; j < body.interfaces[k].nodes.size(); ++j)
      owner[body.interfaces[k].nodes(j)] = static_cast<std::int32_t>(k + 1);
  out.point_array("interface", owner);
  std::vector<double> points(mesh.nodes.data(), mesh.nodes.data() + mesh.nodes.size());  // row-major x, y, z
  out.points(points);
  // Quadratic tetrahedra as VTK's (type 24, the same node order): ParaView draws their curved faces.
  out.cells(std::vector<std::int64_t>(mesh.tets.data(), mesh.tets.data() + mesh.tets.size()),
            static_cast<int>(mesh.tets.cols()), quadratic ? format::kVtkQuadraticTetra : format::kVtkTetra);
  out.commit();
}

}  // namespace flexbody::preprocess
