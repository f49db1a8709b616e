#include "calculix.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace flexbody::test {

bool have_ccx() { return std::system("command -v ccx > /dev/null 2>&1") == 0; }

bool ccx_required() { return std::getenv("FLEXBODY_REQUIRE_CCX") != nullptr; }

void write_inp(const std::filesystem::path& path, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
               const Eigen::Ref<const Eigen::MatrixXi>& tets, double youngs_modulus, double poisson_ratio, double density,
               const std::string& rest) {
  std::ofstream inp(path);
  inp << "*NODE\n";
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    // 14 digits: ccx reads at most 20 characters per number (-5.2041704279304213E-18 was refused).
    inp << fmt::format("{}, {:.14g}, {:.14g}, {:.14g}\n", i + 1, nodes(i, 0), nodes(i, 1), nodes(i, 2));
  inp << "*ELEMENT, TYPE=" << (tets.cols() == 10 ? "C3D10" : "C3D4") << ", ELSET=EALL\n";
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    inp << e + 1;
    for (Eigen::Index a = 0; a < tets.cols(); ++a) inp << ", " << tets(e, a) + 1;
    inp << "\n";
  }
  inp << fmt::format("*NSET, NSET=NALL, GENERATE\n1, {}\n", nodes.rows());
  inp << fmt::format("*MATERIAL, NAME=STEEL\n*ELASTIC\n{:.14g}, {:.14g}\n*DENSITY\n{:.14g}\n", youngs_modulus, poisson_ratio,
                     density);
  inp << "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n" << rest;
}

bool run_ccx(const std::filesystem::path& dir, const std::string& job) {
  // One solver thread: CCX_NPROC_EQUATION_SOLVER=2 made its eigen phase erratically slow here.
  const std::string command = fmt::format("cd '{}' && CCX_NPROC_EQUATION_SOLVER=1 OMP_NUM_THREADS=1 ccx -i {} > {}.log 2>&1",
                                          dir.string(), job, job);
  if (std::system(command.c_str()) == 0) return true;
  ADD_FAILURE() << "ccx failed, see " << (dir / (job + ".log"));
  return false;
}

std::vector<double> ccx_frequencies(const std::filesystem::path& dir, const std::string& job,
                                    const Eigen::Ref<const Eigen::MatrixXd>& nodes, const Eigen::Ref<const Eigen::MatrixXi>& tets,
                                    double youngs_modulus, double poisson_ratio, double density,
                                    const Eigen::VectorXi& clamped, double spin, const Eigen::Vector3d& point,
                                    const Eigen::Vector3d& axis, int count) {
  std::string deck = "*BOUNDARY\n";
  for (Eigen::Index k = 0; k < clamped.size(); ++k) deck += fmt::format("{}, 1, 3\n", clamped(k) + 1);
  if (spin > 0.0)  // 14 digits: ccx reads at most 20 characters per number
    deck += fmt::format("*STEP, NLGEOM\n*STATIC\n*DLOAD\nEALL, CENTRIF, {:.14g}, {:.14g}, {:.14g}, {:.14g}, {:.14g}, "
                        "{:.14g}, {:.14g}\n*END STEP\n*STEP, PERTURBATION\n*FREQUENCY\n{}\n*END STEP\n",
                        spin * spin, point.x(), point.y(), point.z(), axis.x(), axis.y(), axis.z(), count);
  else
    deck += fmt::format("*STEP\n*FREQUENCY\n{}\n*END STEP\n", count);
  write_inp(dir / (job + ".inp"), nodes, tets, youngs_modulus, poisson_ratio, density, deck);
  if (!run_ccx(dir, job)) return {};
  std::vector<double> frequencies;
  for (double eigenvalue : read_eigenvalues(dir / (job + ".dat"))) frequencies.push_back(std::sqrt(std::max(eigenvalue, 0.0)));
  return frequencies;
}

std::vector<double> read_eigenvalues(const std::filesystem::path& dat) {
  std::ifstream file(dat);
  std::string line;
  std::vector<double> values;
  bool in_table = false;
  while (std::getline(file, line)) {
    if (line.find("E I G E N V A L U E   O U T P U T") != std::string::npos) {
      in_table = true;
    } else if (line.find("P A R T I C I P A T I O N") != std::string::npos) {
      break;
    } else if (in_table) {
      std::istringstream in(line);
      int mode = 0;
      double eigenvalue = 0.0;
      if (in >> mode >> eigenvalue) values.push_back(eigenvalue);
    }
  }
  return values;
}

Eigen::VectorXd read_displacements(const std::filesystem::path& dat, Eigen::Index nodes) {
  std::ifstream file(dat);
  std::string line;
  Eigen::VectorXd u = Eigen::VectorXd::Constant(3 * nodes, std::nan(""));
  while (std::getline(file, line)) {
    std::istringstream in(line);
    long label = 0;
    double x = 0, y = 0, z = 0;
    if (in >> label >> x >> y >> z && label >= 1 && label <= nodes) u.segment<3>(3 * (label - 1)) << x, y, z;
  }
  return u;
}

}  // namespace flexbody::test
