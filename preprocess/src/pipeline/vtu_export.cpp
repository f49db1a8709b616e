#include "flexbody/preprocess/vtu_export.hpp"

#include "flexbody/preprocess/stress_recovery.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string_view>
#include <unistd.h>
#include <vector>

namespace flexbody::preprocess {
namespace {

constexpr std::uint8_t kVtkTetra = 10;
// Stresses are computed for this many modes at a time: 6 n_n doubles each (48 MB per mode at 1M nodes).
constexpr Eigen::Index kStressModeBlock = 8;
// ParaView's SymmetricTensor order XX, YY, ZZ, XY, YZ, XZ as indices into our Voigt order xx, yy, zz, xy, xz, yz.
constexpr std::array<int, kStressComponents> kParaViewFromVoigt = {0, 1, 2, 3, 5, 4};

// Base64 of a VTK binary block: an 8-byte length header (header_type="UInt64") followed by the data.
std::string base64_block(const void* data, std::size_t bytes) {
  std::vector<unsigned char> raw(8 + bytes);
  const std::uint64_t length = bytes;
  std::memcpy(raw.data(), &length, 8);
  if (bytes > 0) std::memcpy(raw.data() + 8, data, bytes);
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((raw.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < raw.size(); i += 3) {
    const std::uint32_t a = raw[i], b = i + 1 < raw.size() ? raw[i + 1] : 0, c = i + 2 < raw.size() ? raw[i + 2] : 0;
    const std::uint32_t triple = (a << 16) | (b << 8) | c;
    out += kAlphabet[(triple >> 18) & 63];
    out += kAlphabet[(triple >> 12) & 63];
    out += i + 1 < raw.size() ? kAlphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < raw.size() ? kAlphabet[triple & 63] : '=';
  }
  return out;
}

template <class T>
void data_array(std::ofstream& out, const char* type, const std::string& name, int components, const std::vector<T>& values) {
  out << fmt::format("        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"binary\">\n", type,
                     name, components)
      << "          " << base64_block(values.data(), values.size() * sizeof(T)) << "\n        </DataArray>\n";
}

}  // namespace

std::string mode_array_name(int m, double frequency_hz) { return fmt::format("mode_{:02d}_{:.6g}Hz", m + 1, frequency_hz); }

std::string stress_array_name(int m, double frequency_hz) {
  return "stress_" + mode_array_name(m, frequency_hz).substr(std::string_view("mode_").size());
}

std::string mises_array_name(int m) { return fmt::format("mises_{:02d}", m + 1); }

void write_body_vtu(const format::BodyData& body, const std::filesystem::path& path) {
  const auto& mesh = body.mesh;
  const Eigen::Index n_n = mesh.nodes.rows(), n_e = mesh.tets.rows();
  const std::filesystem::path temporary =
      path.parent_path() / fmt::format(".{}.tmp-{}", path.filename().string(), ::getpid());
  try {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot be written", path.string()));
    out << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        << "  <UnstructuredGrid>\n"
        << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n_n, n_e);
    out << "      <PointData>\n";
    std::vector<double> vectors(static_cast<std::size_t>(3 * n_n)), tensors(static_cast<std::size_t>(6 * n_n)),
        mises(static_cast<std::size_t>(n_n));
    const TetMesh tet_mesh{mesh.nodes, mesh.tets};
    for (Eigen::Index first = 0; first < body.modes.count(); first += kStressModeBlock) {
      const Eigen::Index block = std::min(kStressModeBlock, body.modes.count() - first);
      Eigen::MatrixXd displacements(3 * n_n, block);  // node-interleaved columns of Ῡ
      for (Eigen::Index c = 0; c < block; ++c)
        for (Eigen::Index i = 0; i < n_n; ++i)
          for (int k = 0; k < 3; ++k) displacements(3 * i + k, c) = body.modes.upsilon(i, 3 * (first + c) + k);
      const Eigen::MatrixXd stresses = nodal_stresses(tet_mesh, body.material, displacements);
      for (Eigen::Index c = 0; c < block; ++c) {
        const int m = static_cast<int>(first + c);
        const double frequency = body.modes.frequencies_hz(m);
        for (Eigen::Index i = 0; i < n_n; ++i)
          for (int k = 0; k < 3; ++k) vectors[3 * i + k] = displacements(3 * i + k, c);
        data_array(out, "Float64", mode_array_name(m, frequency), 3, vectors);
        for (Eigen::Index i = 0; i < n_n; ++i) {
          const Eigen::Matrix<double, kStressComponents, 1> s = stresses.col(c).segment<kStressComponents>(6 * i);
          for (int k = 0; k < kStressComponents; ++k) tensors[6 * i + k] = s(kParaViewFromVoigt[k]);
          mises[i] = von_mises(s);
        }
        data_array(out, "Float64", stress_array_name(m, frequency), 6, tensors);
        data_array(out, "Float64", mises_array_name(m), 1, mises);
      }
    }
    std::vector<double> scalars(static_cast<std::size_t>(n_n));
    for (Eigen::Index f = 0; f < body.gcms.field_count(); ++f) {
      for (Eigen::Index i = 0; i < n_n; ++i) scalars[i] = body.gcms.fields(i, f);
      data_array(out, "Float64", fmt::format("field_{:03d}", f + 1), 1, scalars);
    }
    std::vector<std::int32_t> owner(static_cast<std::size_t>(n_n), 0);
    for (std::size_t k = 0; k < body.interfaces.size(); ++k)
      for (Eigen::Index j = 0; j < body.interfaces[k].nodes.size(); ++j)
        owner[body.interfaces[k].nodes(j)] = static_cast<std::int32_t>(k + 1);
    data_array(out, "Int32", "interface", 1, owner);
    out << "      </PointData>\n      <Points>\n";
    std::vector<double> points(mesh.nodes.data(), mesh.nodes.data() + mesh.nodes.size());  // row-major x, y, z
    data_array(out, "Float64", "Points", 3, points);
    out << "      </Points>\n      <Cells>\n";
    std::vector<std::int64_t> connectivity(mesh.tets.data(), mesh.tets.data() + mesh.tets.size()), offsets(n_e);
    for (Eigen::Index e = 0; e < n_e; ++e) offsets[e] = 4 * (e + 1);
    data_array(out, "Int64", "connectivity", 1, connectivity);
    data_array(out, "Int64", "offsets", 1, offsets);
    data_array(out, "UInt8", "types", 1, std::vector<std::uint8_t>(static_cast<std::size_t>(n_e), kVtkTetra));
    out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    out.close();
    if (!out) throw std::runtime_error(fmt::format("{}: writing failed (disk full?)", path.string()));
    std::filesystem::rename(temporary, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

}  // namespace flexbody::preprocess
