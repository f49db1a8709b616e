// order_bench: linear against quadratic tetrahedra (issue 15), frequency error against DOFs and against the time of
// meshing, assembly and the free-free eigen solve (the stages of fbprep that depend on the element order).
//
//   order_bench OUTPUT.csv [WORK_DIR]
//
// The steel beam 1 x 0.05 x 0.05 m (validation/README.md) on structured Kuhn-split box meshes, against Timoshenko's
// first two bending pairs (263.46 and 714.57 Hz); and the bundled bracket (meshes/bracket.step, mm) meshed by gmsh at
// several sizes, both orders, against its finest quadratic mesh. One CPU thread's worth of work on this 2-core machine;
// each figure is one run (the stages take seconds, the machine's noise is a few per cent).
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Row {
  std::string part;
  int order = 1;
  std::string mesh;  ///< cells, or the gmsh element size
  Eigen::Index dofs = 0;
  double mesh_s = 0.0, assembly_s = 0.0, eigen_s = 0.0;
  Eigen::VectorXd frequencies_hz;
};

// The first `modes` free-free frequencies of K̄, M_s, timed.
void solve(Row& row, const fp::RowMatrixX3d& nodes, const fp::SparseMatrix& k, const fp::SparseMatrix& m, int modes) {
  fp::FreeFreeOptions options;
  options.modes = modes;
  const auto start = std::chrono::steady_clock::now();
  row.frequencies_hz = fp::free_free_modes(nodes, k, m, kSteel, options).frequencies_hz;
  row.eigen_s = seconds_since(start);
  row.dofs = 3 * nodes.rows();
}

Row beam(int order, int nx, int n) {
  Row row;
  row.part = "beam";
  row.order = order;
  row.mesh = std::to_string(nx) + "x" + std::to_string(n) + "x" + std::to_string(n);
  auto start = std::chrono::steady_clock::now();
  const fp::TetMesh linear = fp::box_mesh(1.0, 0.05, 0.05, nx, n, n);
  if (order == 1) {
    row.mesh_s = seconds_since(start);
    start = std::chrono::steady_clock::now();
    const fp::NodeGraph graph = fp::NodeGraph::build(linear);
    const auto geometry = fp::element_geometries(linear);
    const fp::SparseMatrix k = fp::assemble_stiffness(linear, graph, geometry, kSteel);
    const fp::SparseMatrix m = fp::assemble_scalar_mass(linear, graph, geometry, kSteel.density, fp::MassScheme::consistent);
    row.assembly_s = seconds_since(start);
    solve(row, linear.nodes, k, m, 4);
    return row;
  }
  const fp::Tet10Mesh quadratic = fp::quadratic_mesh(linear);
  row.mesh_s = seconds_since(start);
  start = std::chrono::steady_clock::now();
  const fp::Tet10Matrices a = fp::assemble_tet10(quadratic, kSteel);
  row.assembly_s = seconds_since(start);
  solve(row, quadratic.nodes, a.stiffness, a.scalar_mass, 4);
  return row;
}

Row bracket(int order, double size_mm) {
  Row row;
  row.part = "bracket";
  row.order = order;
  row.mesh = fmt::format("{:g} mm", size_mm);
  fp::GmshImportOptions options;
  options.mesh_size = size_mm;
  options.order = order;
  auto start = std::chrono::steady_clock::now();
  const fp::ImportedMesh imported =
      fp::import_tet_mesh(std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.step", options);
  row.mesh_s = seconds_since(start);
  start = std::chrono::steady_clock::now();
  if (order == 1) {
    const fp::TetMesh& mesh = imported.mesh;
    const fp::NodeGraph graph = fp::NodeGraph::build(mesh);
    const auto geometry = fp::element_geometries(mesh);
    const fp::SparseMatrix k = fp::assemble_stiffness(mesh, graph, geometry, kSteel);
    const fp::SparseMatrix m = fp::assemble_scalar_mass(mesh, graph, geometry, kSteel.density, fp::MassScheme::consistent);
    row.assembly_s = seconds_since(start);
    solve(row, mesh.nodes, k, m, 6);
    return row;
  }
  const fp::Tet10Matrices a = fp::assemble_tet10(*imported.quadratic, kSteel);
  row.assembly_s = seconds_since(start);
  solve(row, imported.quadratic->nodes, a.stiffness, a.scalar_mass, 6);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: order_bench OUTPUT.csv\n");
    return 2;
  }
  std::vector<Row> rows;
  auto report = [&](Row row) {
    std::printf("%-8s order %d %-12s %8ld DOFs  mesh %6.2f s  assembly %6.2f s  eigen %6.2f s  f = %.6g %.6g %.6g %.6g Hz\n",
                row.part.c_str(), row.order, row.mesh.c_str(), static_cast<long>(row.dofs), row.mesh_s, row.assembly_s,
                row.eigen_s, row.frequencies_hz(0), row.frequencies_hz(1), row.frequencies_hz(2), row.frequencies_hz(3));
    std::fflush(stdout);
    rows.push_back(std::move(row));
  };
  for (const int n : {1, 2, 4, 8, 16}) report(beam(1, 20 * n, n));
  for (const int n : {1, 2, 4, 6}) report(beam(2, 10 * n, n));
  for (const double size : {3.5, 2.2, 1.5, 1.0}) report(bracket(1, size));
  for (const double size : {8.0, 5.0, 3.5, 2.5}) report(bracket(2, size));
  std::ofstream csv(argv[1]);
  csv << "part,order,mesh,dofs,mesh_s,assembly_s,eigen_s,f1_hz,f2_hz,f3_hz,f4_hz,f5_hz,f6_hz\n";
  for (const Row& r : rows) {
    csv << r.part << ',' << r.order << ',' << r.mesh << ',' << r.dofs << ',' << r.mesh_s << ',' << r.assembly_s << ','
        << r.eigen_s;
    for (Eigen::Index k = 0; k < 6; ++k) csv << ',' << (k < r.frequencies_hz.size() ? std::to_string(r.frequencies_hz(k)) : "");
    csv << '\n';
  }
  return 0;
}
