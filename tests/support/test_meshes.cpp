#include "test_meshes.hpp"

#include "flexbody/preprocess/box_mesh.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mass_properties.hpp"

#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <sstream>
#include <unistd.h>
#include <stdexcept>
#include <vector>

namespace flexbody::test {

std::filesystem::path data_dir() { return FLEXBODY_TEST_DATA_DIR; }

std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "flexbody";
  for (char& c : name)
    if (c == '/') c = '_';
  // Under the build tree, named by the test: two build trees can run their suites at the same time (a CI clone
  // beside a working build), and a failed test's files stay for a look until its next run.
  const auto dir = std::filesystem::path(FLEXBODY_TEST_SCRATCH_DIR) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

AssembledMesh assemble(preprocess::TetMesh mesh, const preprocess::Material& material, preprocess::MassScheme scheme) {
  const auto graph = preprocess::NodeGraph::build(mesh);
  const auto geometry = preprocess::element_geometries(mesh);
  AssembledMesh result;
  result.stiffness = preprocess::assemble_stiffness(mesh, graph, geometry, material);
  result.scalar_mass = preprocess::assemble_scalar_mass(mesh, graph, geometry, material.density, scheme);
  result.mesh = std::move(mesh);
  return result;
}

preprocess::TetMesh box_mesh(double lx, double ly, double lz, int nx, int ny, int nz) {
  return preprocess::box_mesh(lx, ly, lz, nx, ny, nz);
}

namespace {

// The first *Node block and the first element block of `type` (N nodes per element, 0-based) of an Abaqus .inp file.
template <int N>
void read_abaqus(const std::filesystem::path& path, const std::string& type, preprocess::RowMatrixX3d& nodes_out,
                 std::vector<std::array<std::int32_t, N>>& elements) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<std::array<double, 3>> nodes;
  enum class Block { none, nodes, elements } block = Block::none;
  std::string line;
  while (std::getline(file, line)) {
    if (line.rfind("**", 0) == 0) continue;
    if (line.rfind('*', 0) == 0) {
      if (line.rfind("*Node", 0) == 0 && nodes.empty()) block = Block::nodes;
      else if (line.find("type=" + type) != std::string::npos && elements.empty()) block = Block::elements;
      else block = Block::none;
      continue;
    }
    for (char& c : line)
      if (c == ',') c = ' ';
    std::istringstream in(line);
    long label = 0;
    in >> label;
    if (block == Block::nodes) {
      std::array<double, 3> x{};
      in >> x[0] >> x[1] >> x[2];
      if (label != static_cast<long>(nodes.size()) + 1) throw std::runtime_error("unexpected node numbering");
      nodes.push_back(x);
    } else if (block == Block::elements) {
      std::array<std::int32_t, N> t{};
      for (auto& n : t) {
        if (!(in >> n)) throw std::runtime_error(path.string() + ": an element of " + type + " with too few nodes");
        --n;
      }
      elements.push_back(t);
    }
  }
  nodes_out.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (int c = 0; c < 3; ++c) nodes_out(static_cast<Eigen::Index>(i), c) = nodes[i][static_cast<std::size_t>(c)];
}

}  // namespace

preprocess::TetMesh read_abaqus_c3d4(const std::filesystem::path& path) {
  preprocess::TetMesh mesh;
  std::vector<std::array<std::int32_t, 4>> tets;
  read_abaqus<4>(path, "C3D4", mesh.nodes, tets);
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t e = 0; e < tets.size(); ++e)
    for (int a = 0; a < 4; ++a) mesh.tets(static_cast<Eigen::Index>(e), a) = tets[e][static_cast<std::size_t>(a)];
  return mesh;
}

preprocess::Tet10Mesh read_abaqus_c3d10(const std::filesystem::path& path) {
  preprocess::Tet10Mesh mesh;
  std::vector<std::array<std::int32_t, 10>> tets;
  read_abaqus<10>(path, "C3D10", mesh.nodes, tets);
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 10);
  for (std::size_t e = 0; e < tets.size(); ++e)
    for (int a = 0; a < 10; ++a) mesh.tets(static_cast<Eigen::Index>(e), a) = tets[e][static_cast<std::size_t>(a)];
  return mesh;
}

preprocess::SparseMatrix read_abaqus_matrix(const std::filesystem::path& path, Eigen::Index size) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<Eigen::Triplet<double, std::int64_t>> triplets;
  long row = 0, col = 0;
  double value = 0.0;
  while (file >> row >> col >> value) triplets.emplace_back(row - 1, col - 1, value);
  preprocess::SparseMatrix matrix(size, size);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  return matrix;
}

const AssembledMesh& square_beam() {
  static const AssembledMesh beam = [] {
    // One file per process: ctest -j runs the tests of a suite in parallel processes.
    const auto path = std::filesystem::temp_directory_path() /
                      ("flexbody-test-square-beam-" + std::to_string(::getpid()) + ".geo");
    std::ofstream(path) << "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.05};\n";
    preprocess::GmshImportOptions options;
    options.unit = preprocess::LengthUnit::metre;
    options.mesh_size = 0.02;
    options.order = 1;  // the linear mesh that `assemble` takes
    preprocess::TetMesh mesh = preprocess::import_tet_mesh(path, options).mesh;
    std::filesystem::remove(path);
    const preprocess::Material steel{"steel", 210e9, 0.3, 7850.0};
    AssembledMesh assembled = assemble(mesh, steel);
    const Eigen::RowVector3d com =
        preprocess::mass_properties(assembled.scalar_mass, assembled.mesh.nodes).center_of_mass_input.transpose();
    assembled.mesh.nodes.rowwise() -= com;  // K̄ and M_s do not change under a translation
    return assembled;
  }();
  return beam;
}

const AssembledMesh& steel_wire() {
  static const AssembledMesh wire =
      assemble(box_mesh(1.0, 0.0025, 0.0025, 100, 1, 1), preprocess::Material{"steel", 210e9, 0.3, 7850.0});
  return wire;
}

preprocess::RigidInterface steel_wire_root() {
  const AssembledMesh& wire = steel_wire();
  std::vector<int> nodes;
  for (Eigen::Index i = 0; i < wire.mesh.nodes.rows(); ++i)
    if (wire.mesh.nodes(i, 0) == 0.0) nodes.push_back(static_cast<int>(i));
  preprocess::RigidInterface root;
  root.nodes = Eigen::Map<const Eigen::VectorXi>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
  root.reference_point = Eigen::Vector3d(0.0, 0.00125, 0.00125);
  return root;
}

}  // namespace flexbody::test
