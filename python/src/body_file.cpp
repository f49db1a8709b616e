// body_file.cpp: flexbody.read_body and the Body it returns: a body file's datasets as read-only NumPy views of the
// reader's storage (format/body_data.hpp, formats/SCHEMA.md), kept alive by the Body.
#include "array_view.hpp"
#include "bindings.hpp"

#include "flexbody/format/body_file.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <memory>
#include <string>
#include <utility>

namespace flexbody::python {
namespace {

struct BodyFile {
  std::filesystem::path path;
  format::BodyData data;
};

const format::BodyData& data_of(const py::object& self) { return self.cast<const BodyFile&>().data; }

// A read-only array property of the Body: `get` picks the Eigen object out of the body data.
template <class Get>
void array_property(py::class_<BodyFile, std::shared_ptr<BodyFile>>& c, const char* name, Get get, const char* doc) {
  c.def_property_readonly(name, [get](const py::object& self) { return view_of(get(data_of(self)), self); }, doc);
}

}  // namespace

void bind_body_file(py::module_& m) {
  // The reader's errors, with its one-line messages: BodyFileDamaged (a seal that does not match the bytes) is a
  // BodyFileError.
  static py::exception<format::BodyFileError> body_file_error(m, "BodyFileError", PyExc_RuntimeError);
  static py::exception<format::BodyFileDamaged> body_file_damaged(m, "BodyFileDamaged", body_file_error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const format::BodyFileDamaged& e) {
      body_file_damaged(e.what());
    } catch (const format::BodyFileError& e) {
      body_file_error(e.what());
    }
  });

  py::class_<format::Interface>(m, "Interface",
                                "A named node set of the body's surface where joints and forces act (rbe2 or rbe3).")
      .def_property_readonly("name", [](const format::Interface& i) { return i.name; })
      .def_property_readonly("coupling", [](const format::Interface& i) { return i.coupling; },
                             "'rbe2' (the nodes move rigidly with the marker) or 'rbe3' (the marker follows their "
                             "weighted average motion)")
      .def_property_readonly("nodes", [](const py::object& self) { return view_of(self.cast<const format::Interface&>().nodes, self); },
                             "(k,) int32: node indices (0-based, ascending) into Body.nodes")
      .def_property_readonly("weights", [](const py::object& self) { return view_of(self.cast<const format::Interface&>().weights, self); },
                             "(k,) float64 [1]: each node's share of the selected surface area; they sum to 1")
      .def_property_readonly("reference_point", [](const py::object& self) { return view_of(self.cast<const format::Interface&>().reference_point, self); },
                             "(3,) float64 [m]: the marker's point, Σ w_i X̄_i, body frame")
      .def_property_readonly("y_row", [](const py::object& self) { return view_of(self.cast<const format::Interface&>().y_row, self); },
                             "(4 + n_f,) float64: the marker's row of Y = [1, X̄, Ῡ'] (its position is (y_rowᵀ ⊗ I3) q)")
      .def_property_readonly("rotation", [](const py::object& self) { return view_of(self.cast<const format::Interface&>().rotation, self); },
                             "(3, 3 n_f) float64 [kg^-1/2 m^-1]: R, the node set's small rotation θ̄ = R ξ̄")
      .def("__repr__", [](const format::Interface& i) {
        return "<flexbody.Interface '" + i.name + "' (" + i.coupling + ", " + std::to_string(i.nodes.size()) + " nodes)>";
      });

  py::class_<format::RecoveryRegion>(m, "OutputRegion", "An output region: stress recovery σ̄ = S ξ̄ at its nodes.")
      .def_property_readonly("name", [](const format::RecoveryRegion& r) { return r.name; })
      .def_property_readonly("nodes", [](const py::object& self) { return view_of(self.cast<const format::RecoveryRegion&>().nodes, self); },
                             "(k,) int32: node indices (0-based, ascending) into Body.nodes")
      .def_property_readonly("stress_modes", [](const py::object& self) { return view_of(self.cast<const format::RecoveryRegion&>().stress_modes, self); },
                             "(6 k, 3 n_f) float64 [Pa kg^-1/2 m^-1]: S; row 6 j + c is stress component c (xx, yy, "
                             "zz, xy, xz, yz) at nodes[j], column 3 f + d the field f along axis d")
      .def("__repr__", [](const format::RecoveryRegion& r) {
        return "<flexbody.OutputRegion '" + r.name + "' (" + std::to_string(r.nodes.size()) + " nodes)>";
      });

  py::class_<BodyFile, std::shared_ptr<BodyFile>> body(
      m, "Body",
      "A flexible body file (*.fbh5) as read and validated. Its arrays are read-only views of the reader's storage "
      "(no copies), valid as long as any of them or the Body lives. SI units: metres, kilograms, seconds, pascals.");
  body.def_property_readonly("path", [](const BodyFile& b) { return b.path; })
      .def_property_readonly("format_version", [](const BodyFile& b) { return b.data.format_version; },
                             "the file's schema version (formats/SCHEMA.md)")
      .def_property_readonly("sealed", [](const BodyFile& b) { return b.data.sealed; },
                             "whether the file carried a seal that matched its bytes")
      .def_property_readonly("unit", [](const BodyFile&) { return std::string("m"); },
                             "the unit of every length in the file: always 'm' (SI); provenance['input_unit'] is the "
                             "unit the CAD was read in")
      .def_property_readonly(
          "provenance",
          [](const BodyFile& b) {
            const format::Provenance& p = b.data.provenance;
            py::dict d;
            d["created_by"] = p.created_by;
            d["created_utc"] = p.created_utc;
            d["source_file"] = p.source_file;
            d["source_sha256"] = p.source_sha256;
            d["input_unit"] = p.input_unit;
            d["unit_reason"] = p.unit_reason;
            d["declared_unit"] = p.declared_unit;
            py::dict options;
            for (const auto& [key, value] : p.options) options[py::str(key)] = value;
            d["options"] = options;
            return d;
          },
          "where the file came from: created_by, created_utc, source_file, source_sha256, input_unit, unit_reason, "
          "declared_unit and the tool's options (name: value as text)")
      .def_property_readonly(
          "material",
          [](const BodyFile& b) {
            const format::Material& mat = b.data.material;
            py::dict d;
            d["name"] = mat.name;
            d["youngs_modulus"] = mat.youngs_modulus;
            d["poisson_ratio"] = mat.poisson_ratio;
            d["density"] = mat.density;
            return d;
          },
          "name, youngs_modulus [Pa], poisson_ratio [1], density [kg/m^3]")
      .def_property_readonly("mass", [](const BodyFile& b) { return b.data.mass.mass; }, "[kg]")
      .def_property_readonly("element_order", [](const BodyFile& b) { return b.data.mesh.element_order; },
                             "1: linear tetrahedra (4 nodes), 2: quadratic (10 nodes)")
      .def_property_readonly("mode_kind", [](const BodyFile& b) { return b.data.modes.kind; },
                             "'free-free' or 'craig-bampton'")
      .def_property_readonly("eigensolver", [](const BodyFile& b) { return b.data.modes.eigensolver; })
      .def_property_readonly("static_correction_modes", [](const BodyFile& b) { return b.data.modes.static_correction_modes; },
                             "free-free only: the last this many modes are static correction modes (Ritz vectors)");
  array_property(body, "center_of_mass", [](const format::BodyData& d) -> const auto& { return d.mass.center_of_mass_input; },
                 "(3,) float64 [m]: the centre of mass in the input (CAD) frame; the body frame's origin");
  array_property(body, "inertia", [](const format::BodyData& d) -> const auto& { return d.mass.inertia_about_com; },
                 "(3, 3) float64 [kg m^2]: the inertia tensor about the centre of mass, body axes");
  array_property(body, "nodes", [](const format::BodyData& d) -> const auto& { return d.mesh.nodes; },
                 "(n_n, 3) float64 [m]: the mesh's nodes in the body frame (origin at the centre of mass, axes "
                 "parallel to the input's)");
  array_property(body, "elements", [](const format::BodyData& d) -> const auto& { return d.mesh.tets; },
                 "(n_e, 4 or 10) int32: tetrahedra, 0-based node indices (quadratic: corners, then edge middles)");
  array_property(body, "surface_triangles", [](const format::BodyData& d) -> const auto& { return d.mesh.surface_triangles; },
                 "(n_t, 3) int32: the boundary, counter-clockwise seen from outside");
  array_property(body, "frequencies_hz", [](const format::BodyData& d) -> const auto& { return d.modes.frequencies_hz; },
                 "(n_m,) float64 [Hz]: the elastic modes' frequencies, ascending");
  array_property(body, "relative_residuals", [](const format::BodyData& d) -> const auto& { return d.modes.relative_residuals; },
                 "(n_m,) float64 [1]: ||K φ − ω² M φ|| / ||K φ|| per mode");
  array_property(body, "fixed_interface_frequencies_hz",
                 [](const format::BodyData& d) -> const auto& { return d.modes.fixed_interface_frequencies_hz; },
                 "(k,) float64 [Hz]: Craig-Bampton only (else empty): the frequencies with every rbe2 interface held");
  array_property(body, "upsilon", [](const format::BodyData& d) -> const auto& { return d.modes.upsilon; },
                 "(n_n, 3 n_m) float64 [kg^-1/2]: Ῡ (Eq. 49), row i = [ψ_1(i)ᵀ ... ψ_n_m(i)ᵀ], M-orthonormal modes");
  body.def_property_readonly(
      "mode_shapes",
      [](const py::object& self) {
        const Eigen::MatrixXd& u = data_of(self).modes.upsilon;
        const py::ssize_t n = u.rows(), modes = u.cols() / 3;
        return read_only<double>(u.data(), {modes, n, 3}, {3 * n, 1, n}, self);
      },
      "(n_m, n_n, 3) float64 [kg^-1/2]: mode m's displacement at node i along x, y, z (the same storage as upsilon)");
  array_property(body, "fields", [](const format::BodyData& d) -> const auto& { return d.gcms.fields; },
                 "(n_n, n_f) float64 [kg^-1/2]: Ῡ', the GCMS fields, M_s-orthonormal");
  array_property(body, "field_mode", [](const format::BodyData& d) -> const auto& { return d.gcms.field_mode; },
                 "(n_f,) int32: the mode each field came from (the first k modes use the fields with field_mode < k)");
  array_property(body, "mode_coefficients", [](const format::BodyData& d) -> const auto& { return d.gcms.mode_coefficients; },
                 "(n_f, 3 n_m) float64 [1]: C = Ῡ'ᵀ M_s Ῡ");
  array_property(body, "G", [](const format::BodyData& d) -> const auto& { return d.gcms.mass_matrix; },
                 "(4 + n_f, 4 + n_f) float64: G = Yᵀ M_s Y (Eq. 66); blocks in kg, kg m, kg m^2, kg^1/2 m, 1");
  array_property(body, "K_hat", [](const format::BodyData& d) -> const auto& { return d.gcms.stiffness; },
                 "(3 n_f, 3 n_f) float64 [1/s^2]: K̂ (Eq. 96), index 3 f + k");
  body.def_property_readonly(
      "interfaces",
      [](const py::object& self) {
        py::dict d;
        for (const format::Interface& i : data_of(self).interfaces)
          d[py::str(i.name)] = py::cast(&i, py::return_value_policy::reference_internal, self);
        return d;
      },
      "name -> Interface, in the body spec's order");
  body.def_property_readonly(
      "output_regions",
      [](const py::object& self) {
        py::dict d;
        for (const format::RecoveryRegion& r : data_of(self).recovery)
          d[py::str(r.name)] = py::cast(&r, py::return_value_policy::reference_internal, self);
        return d;
      },
      "name -> OutputRegion (stress recovery), in the body spec's order");
  body.def_property_readonly(
      "geometric_stiffness",
      [](const py::object& self) {
        const format::GeometricStiffness& g = data_of(self).geometric_stiffness;
        py::dict d;
        for (std::size_t k = 0; k < g.cases.size(); ++k) d[py::str(g.cases[k])] = view_of(g.matrices[k], self);
        return d;
      },
      "case -> Ĝ_k ((4 + n_f) square) per unit λ_k ('centrifugal:xx' ... and '<interface>:fx' ...); empty "
      "unless fbprep wrote it (--geometric-stiffness)");
  body.def("__repr__", [](const BodyFile& b) {
    return "<flexbody.Body '" + b.path.filename().string() + "': " + std::to_string(b.data.mesh.nodes.rows()) +
           " nodes, " + std::to_string(b.data.modes.count()) + " " + b.data.modes.kind + " modes>";
  });

  m.def(
      "read_body",
      [](const std::filesystem::path& path, bool require_seal) {
        auto b = std::make_shared<BodyFile>();
        b->path = path;
        format::ReadOptions options;
        options.require_seal = require_seal;
        b->data = format::read_body_file(path, options);  // with the GIL held: the reader is not made for threads
        return b;
      },
      py::arg("path"), py::arg("require_seal") = true,
      "Reads and validates a body file. Raises BodyFileError (BodyFileDamaged for a seal that does not match the "
      "file's bytes) with the reader's one-line message.");
}

}  // namespace flexbody::python
