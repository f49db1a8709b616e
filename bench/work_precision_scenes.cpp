// The four scenes of work_precision_bench and the parts they are made of (work_precision_scenes.hpp).
#include "work_precision_scenes.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/full_order.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace work_precision {
namespace fp = flexbody::preprocess;
namespace {

// A mesh with its matrices, nodes about the centre of mass.
struct Part {
  fp::TetMesh mesh;  // input frame
  fp::SparseMatrix k, m_s;
  flexbody::format::MassProperties mass;
  fp::RowMatrixX3d nodes;  // body frame
  fp::Material material;
};

Part make_part(const fp::Material& material, double lx, double ly, double lz, int nx, int ny, int nz) {
  Part p;
  p.material = material;
  p.mesh = fp::box_mesh(lx, ly, lz, nx, ny, nz);
  const fp::NodeGraph graph = fp::NodeGraph::build(p.mesh);
  const auto geometry = fp::element_geometries(p.mesh);
  p.k = fp::assemble_stiffness(p.mesh, graph, geometry, material);
  p.m_s = fp::assemble_scalar_mass(p.mesh, graph, geometry, material.density, fp::MassScheme::consistent);
  p.mass = fp::mass_properties(p.m_s, p.mesh.nodes);
  p.nodes = p.mesh.nodes.rowwise() - p.mass.center_of_mass_input.transpose();
  return p;
}

Eigen::Index nearest(const Part& p, const Eigen::Vector3d& input_point) {
  Eigen::Index k = 0;
  (p.mesh.nodes.rowwise() - input_point.transpose()).rowwise().squaredNorm().minCoeff(&k);
  return k;
}

// The body data of a part with `modes` modes: free-free, or Craig-Bampton with the nodes `root` as an rbe2 interface
// named "root".
flexbody::format::BodyData body_data(const Part& p, int modes, const std::vector<int>& root) {
  flexbody::format::BodyData b;
  b.mass = p.mass;
  b.mesh.nodes = p.nodes;
  b.mesh.tets = p.mesh.tets;
  if (root.empty()) {
    fp::FreeFreeOptions options;
    options.modes = modes;
    const fp::FreeFreeModes m = fp::free_free_modes(p.nodes, p.k, p.m_s, p.material, options);
    b.modes.frequencies_hz = m.frequencies_hz;
    b.modes.upsilon = fp::upsilon_from_modes(m.vectors);
  } else {
    fp::RigidInterface clamp;
    clamp.nodes = Eigen::Map<const Eigen::VectorXi>(root.data(), static_cast<Eigen::Index>(root.size()));
    for (int i : root) clamp.reference_point += p.nodes.row(i).transpose() / static_cast<double>(root.size());
    fp::CraigBamptonOptions options;
    options.fixed_interface_modes = modes;
    const fp::CraigBamptonModes cb = fp::craig_bampton_modes(p.nodes, p.k, p.m_s, p.material, {clamp}, options);
    b.modes.frequencies_hz = cb.frequencies_hz;
    b.modes.fixed_interface_frequencies_hz = cb.fixed_interface_frequencies_hz;
    b.modes.upsilon = fp::upsilon_from_modes(cb.vectors);
  }
  b.gcms = fp::gcms_constants(p.k, p.m_s, p.nodes, b.modes.upsilon);
  if (!root.empty()) {
    const Eigen::VectorXi nodes = Eigen::Map<const Eigen::VectorXi>(root.data(), static_cast<Eigen::Index>(root.size()));
    const fp::SurfacePatch patch{nodes, Eigen::VectorXd::Constant(nodes.size(), 1.0 / static_cast<double>(nodes.size()))};
    b.interfaces.push_back(fp::interface_marker("root", "rbe2", patch, p.nodes, b.gcms.fields));
  }
  return b;
}

// The body as `kind` with `modes` modes and stiffness-proportional damping D̂ = β K̂ (β K̄ for the full-order body; the
// FFRF's modal damping is then β ω_m², so every model damps the same modes alike).
fr::BodyModel model_of(const Part& p, const flexbody::format::BodyData* data, Kind kind, int modes, double beta = 0.0) {
  if (kind == Kind::full_order) {
    fr::BodyModel full = fr::full_order_model(fp::full_from_upper(p.k), fp::full_from_upper(p.m_s), p.nodes);
    return beta > 0.0 ? fr::damp_full_order(std::move(full), beta) : full;
  }
  fr::BodyModel model = fr::make_body_model(*data, modes, "part");
  if (beta > 0.0) model.damping = fr::rayleigh_damping(model, 0.0, beta);
  if (kind == Kind::ffrf_mean_axis)
    model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
  if (kind == Kind::ffrf_interface)
    model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::interface, "root"));
  return model;
}

// A tiny rigid body (a hub) of mass m and gyration radius r, its centre at the origin of its frame.
fr::BodyModel hub_model(double mass, double radius) {
  return fr::rigid_body_model(mass, Eigen::Matrix3d::Identity() * mass * radius * radius, "hub");
}

}  // namespace

// Scene 1: a flexible pendulum. A bar 1 x 0.02 x 0.04 m (E 5e9 Pa, ρ 1000 kg/m³; 40 x 2 x 4 Kuhn-split cells, 615
// nodes, 1845 DOFs), Craig-Bampton with its end face x = 0 an rbe2 interface, pinned there about z, released
// horizontal under gravity −y, 0.5 s: it swings in the plane of its thin side (0.02 m), so its first clamped bending
// mode in the swing plane is about 7 Hz and it sags by about 7 mm, and the frame's effect, second order in the
// deformation, shows. The full-order reference: every root
// node tied by a spherical joint to a light rigid hub (1e-4 of the bar's mass, centred on the axis) that turns about
// the same axis: the rbe2 root. Every model is damped by D̂ = β K̂ with β = 1e-4 s (ζ = βω/2: 0.2 % in the first mode, 8 %
// at 250 Hz): the sudden release excites every mode of the mesh, and undamped, the phase of the modes above 100 Hz
// after 0.5 s is not converged even in the reference (at 250 Hz and h = 7.8e-5 s the period error (ωh)²/12 = 0.1 %
// is 0.15 cycles over the run), so the errors would measure that, not the models.
Scene scene_pendulum(bool quick) {
  static const Part part = make_part({"soft", 5e9, 0.3, 1000.0}, 1.0, 0.02, 0.04, 40, 2, 4);
  static std::vector<int> root;
  if (root.empty())
    for (Eigen::Index i = 0; i < part.nodes.rows(); ++i)
      if (part.mesh.nodes(i, 0) == 0.0) root.push_back(static_cast<int>(i));
  static const flexbody::format::BodyData data = body_data(part, 32, root);
  Scene s;
  s.name = "pendulum";
  s.end = 0.5;
  s.sample = 0.01;
  s.steps = quick ? std::vector<double>{5e-3, 1.25e-3} : std::vector<double>{5e-3, 2.5e-3, 1.25e-3, 6.25e-4, 3.125e-4};
  s.reference_step = quick ? 3.125e-4 : 7.8125e-5;
  s.modes = quick ? std::vector<int>{2, 8} : std::vector<int>{2, 4, 8, 16, 32};
  s.kinds = {Kind::gcms, Kind::ffrf_mean_axis, Kind::ffrf_interface};
  s.tolerances = quick ? std::vector<double>{1e-6, 1e-8} : std::vector<double>{1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  s.build = [](Kind kind, int modes) {
    auto b = std::make_unique<Built>();
    const fr::BodyModel model = model_of(part, &data, kind, modes, 1e-4);
    b->body = b->system.add_body("bar", model, fr::BodyState{});
    const fr::BodyModel& m = b->system.model(b->body);
    b->tip = fr::node_marker(m, b->body, "bar", nearest(part, {1.0, 0.01, 0.02}));
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    for (int i : root) center += part.nodes.row(i).transpose() / static_cast<double>(root.size());
    if (kind == Kind::full_order) {
      fr::BodyState at_root;
      at_root.position = center;
      const int hub = b->system.add_body("hub", hub_model(1e-4 * part.mass.mass, 0.01), at_root);
      const Eigen::VectorXd q0 = b->system.initial_coordinates();
      const Eigen::VectorXd q_hub = b->system.body_coordinates(q0, hub), q_bar = b->system.body_coordinates(q0, b->body);
      b->joint = 0;
      b->system.add_joint(fr::make_joint("pin", fr::JointType::revolute, fr::point_marker(b->system.model(hub), hub, "hub", Eigen::Vector3d::Zero()),
                                         fr::ground_marker(center), Eigen::Vector3d::UnitZ(), q_hub, Eigen::VectorXd()));
      for (int i : root) {
        const fr::Marker node = fr::node_marker(m, b->body, "bar", i);
        b->system.add_joint(fr::make_joint("tie " + std::to_string(i), fr::JointType::spherical,
                                           fr::point_marker(b->system.model(hub), hub, "hub", part.nodes.row(i).transpose() - center),
                                           node, Eigen::Vector3d::UnitZ(), q_hub, q_bar));
      }
    } else {
      const fr::Marker pin = fr::interface_marker(m, b->body, "bar", "root");
      const Eigen::VectorXd q0 = b->system.initial_coordinates();
      b->joint = 0;
      b->system.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                         Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
    }
    b->system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
    return b;
  };
  return s;
}

// Scene 2: a slider-crank whose connecting rod is flexible. The rod 0.6 x 0.01 x 0.02 m (E 5e9 Pa, ρ 1000 kg/m³,
// 0.12 kg; 60 x 2 x 2 Kuhn-split cells, 549 nodes, 1647 DOFs) bends in the plane of the mechanism about its thin side;
// Craig-Bampton with its end faces as rbe2 interfaces (the bores: "crank" at x = 0, "slider" at x = 0.6). A rigid crank
// (1 kg, gyration radius 0.05 m, radius r = 0.15 m) is driven about z at the origin; the rod's ends are held by
// a spherical joint to the crank pin and a revolute joint (about z) to a rigid slider (0.05 kg), which slides along x on
// a carriage (0.5 kg) that may slide along z: a planar loop of revolute joints in 3D repeats three rows, and closed
// with two spherical ends it leaves the rod's spin about its own axis free, with a tiny inertia (5e-6 kg m²) that the
// bending excites (measured: 90 rad/s of spin and a failed Newton iteration within 1 s); the carriage's z freedom is
// the row the revolute wrist adds, and nothing drives it out of the plane. The crank speeds up with
// φ̇ = Ω (1 − cos πt/T) / 2 to Ω = 0.25 ω_pp at T = 1 s,
// ω_pp the rod's first pinned-pinned bending frequency (the free-free one / 2.267, Euler-Bernoulli's ratio). Not
// through the rod's resonance: the crank's inertia loads compress the rod by up to (m_slider + m_rod/2) Ω² r, which is
// (m_slider/m_rod + 1/2) π² (Ω/ω_pp)² r/L = 2.3 (Ω/ω_pp)² of its buckling load: 0.14 here, 0.57 at Ω = ω_pp/2 (the
// second harmonic in resonance; fbsim stops such a run at its deformation limit, measured: 2 % RMS at 114 rad/s),
// above buckling at ω_pp, where no linear model holds (bench/README.md). No gravity.
// Quantities: the rod's midspan path and the force at the crank pin. Every model is damped by D̂ = β K̂ with ζ = 2 % at
// ω_pp (β = 0.04 / ω_pp). The full-order reference is fbsim's `modes: full` of the Craig-Bampton body file: its rbe2 ends
// move affinely, the span the GCMS's Craig-Bampton fields have there (full_order.hpp), so it is the limit the GCMS
// approaches; the FFRF's modes hold the ends rigid to first order, a difference of second order in the deformation.
// (Tying each end to a light hub as the other scenes do made the reference's Newton iteration fail at t = 0.85 s: the
// hubs of 1e-3 of the rod's mass on the rod's free spin.)
Scene scene_slider_crank(bool quick) {
  static const Part part = make_part({"soft", 5e9, 0.3, 1000.0}, 0.6, 0.01, 0.02, 60, 2, 2);
  static std::vector<int> crank_end, slider_end;
  if (crank_end.empty())
    for (Eigen::Index i = 0; i < part.nodes.rows(); ++i) {
      if (part.mesh.nodes(i, 0) == 0.0) crank_end.push_back(static_cast<int>(i));
      if (part.mesh.nodes(i, 0) == 0.6) slider_end.push_back(static_cast<int>(i));
    }
  static const flexbody::format::BodyData data = [] {
    flexbody::format::BodyData b = body_data(part, 1, {});  // free-free: for ω_pp only
    return b;
  }();
  static const double omega_pp = 2.0 * 3.141592653589793 * data.modes.frequencies_hz(0) / 2.267;
  // Craig-Bampton with k fixed-interface modes and the 12 constraint modes of the two ends (less the 6 rigid ones): k + 6
  // modes in all, as an Adams or Abaqus user reduces a rod. (Truncating one large basis by frequency instead drops
  // constraint modes, whose Ritz frequencies are high: measured 0.77 % of the travel at 16 of 32 modes, 0.025 % at 32.)
  static std::map<int, flexbody::format::BodyData> bases;
  auto cb = [](int modes) -> const flexbody::format::BodyData& {
    auto found = bases.find(modes);
    if (found != bases.end()) return found->second;
    flexbody::format::BodyData b;
    b.mass = part.mass;
    b.material = {"custom", part.material.youngs_modulus, part.material.poisson_ratio, part.material.density};
    b.mesh.nodes = part.nodes;
    b.mesh.tets = part.mesh.tets;
    std::vector<fp::RigidInterface> ends(2);
    const std::vector<int>* sets[2] = {&crank_end, &slider_end};
    for (int e = 0; e < 2; ++e) {
      ends[e].nodes = Eigen::Map<const Eigen::VectorXi>(sets[e]->data(), static_cast<Eigen::Index>(sets[e]->size()));
      for (int i : *sets[e]) ends[e].reference_point += part.nodes.row(i).transpose() / static_cast<double>(sets[e]->size());
    }
    fp::CraigBamptonOptions options;
    options.fixed_interface_modes = modes - 6;
    const fp::CraigBamptonModes m = fp::craig_bampton_modes(part.nodes, part.k, part.m_s, part.material, ends, options);
    b.modes.frequencies_hz = m.frequencies_hz;
    b.modes.fixed_interface_frequencies_hz = m.fixed_interface_frequencies_hz;
    b.modes.upsilon = fp::upsilon_from_modes(m.vectors);
    b.gcms = fp::gcms_constants(part.k, part.m_s, part.nodes, b.modes.upsilon);
    const char* names[2] = {"crank", "slider"};
    for (int e = 0; e < 2; ++e) {
      const fp::SurfacePatch patch{ends[e].nodes, Eigen::VectorXd::Constant(ends[e].nodes.size(), 1.0 / static_cast<double>(ends[e].nodes.size()))};
      b.interfaces.push_back(fp::interface_marker(names[e], "rbe2", patch, part.nodes, b.gcms.fields));
    }
    return bases.emplace(modes, std::move(b)).first->second;
  };
  std::printf("slider-crank: rod's first modes (two rbe2 ends) %.4g, %.4g Hz; free-free %.4g Hz, so w_pp = %.4g rad/s "
              "(%.4g Hz); crank speed up to %.4g rad/s\n", cb(32).modes.frequencies_hz(0), cb(32).modes.frequencies_hz(1),
              data.modes.frequencies_hz(0), omega_pp, omega_pp / (2.0 * 3.141592653589793), 0.25 * omega_pp);
  Scene s;
  s.name = "slider-crank";
  s.end = 1.0;
  s.sample = 0.01;
  s.steps = quick ? std::vector<double>{5e-4, 2.5e-4} : std::vector<double>{2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4};
  s.reference_step = quick ? 1.25e-4 : 3.125e-5;
  s.modes = quick ? std::vector<int>{7, 12} : std::vector<int>{7, 8, 12, 20, 32};
  s.kinds = {Kind::gcms, Kind::ffrf_mean_axis, Kind::ffrf_interface};
  s.tolerances = quick ? std::vector<double>{1e-6, 1e-8} : std::vector<double>{1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  s.build = [cb](Kind kind, int modes) {
    constexpr double r = 0.15, length = 0.6;
    auto b = std::make_unique<Built>();
    const double beta = 0.04 / omega_pp;
    fr::BodyModel rod_model;
    if (kind == Kind::full_order) {
      rod_model = fr::damp_full_order(fr::full_order_model(cb(32), "rod"), beta);
    } else {
      rod_model = fr::make_body_model(cb(modes), std::nullopt, "rod");
      rod_model.damping = fr::rayleigh_damping(rod_model, 0.0, beta);
      if (kind != Kind::gcms)
        rod_model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(
            rod_model, kind == Kind::ffrf_mean_axis ? fr::FloatingFrame::mean_axis : fr::FloatingFrame::interface, "crank"));
    }
    Eigen::Vector3d crank_face = Eigen::Vector3d::Zero();  // the crank end's centre, body frame
    for (int i : crank_end) crank_face += part.nodes.row(i).transpose() / static_cast<double>(crank_end.size());
    const Eigen::Vector3d rod_at = Eigen::Vector3d(r, 0, 0) - crank_face;  // that centre at the crank pin
    fr::BodyState rod;
    rod.position = rod_at;
    b->body = b->system.add_body("rod", rod_model, rod);
    const int crank = b->system.add_body("crank", hub_model(1.0, 0.05), fr::BodyState{});
    fr::BodyState slider_state;
    slider_state.position = Eigen::Vector3d(r + length, 0, 0);
    const int slider = b->system.add_body("slider", hub_model(0.05, 0.01), slider_state);
    // The carriage never moves (the mechanism stays in its plane), so its mass does not enter the results; at 0.01 kg
    // and 1e-6 kg m² the stabilised index-2 iteration needs its coupled step, which costs more (docs/limits.md).
    const int carriage = b->system.add_body("carriage", hub_model(0.5, 0.05), slider_state);
    const fr::BodyModel& m = b->system.model(b->body);
    b->tip = fr::node_marker(m, b->body, "rod", nearest(part, {0.3, 0.005, 0.01}));
    auto angle = [](double t) {  // φ̇ = Ω (1 − cos πt/T) / 2 up to T, then Ω
      constexpr double ramp = 1.0, pi = 3.141592653589793;
      const double omega = 0.25 * omega_pp;
      if (t >= ramp) return omega * (t - 0.5 * ramp);
      return 0.5 * omega * (t - ramp / pi * std::sin(pi * t / ramp));
    };
    const int crank_side = b->body, slider_side = b->body;
    const fr::Marker crank_end_marker = fr::interface_marker(m, b->body, "rod", "crank");
    const fr::Marker slider_end_marker = fr::interface_marker(m, b->body, "rod", "slider");
    const Eigen::VectorXd q0 = b->system.initial_coordinates();
    auto q_of = [&](int body) { return Eigen::VectorXd(b->system.body_coordinates(q0, body)); };
    b->joint = b->system.joints().size();  // the crank pin, first of the mechanism's joints
    b->system.add_joint(fr::make_joint("pin", fr::JointType::spherical, crank_end_marker,
                                       fr::point_marker(b->system.model(crank), crank, "crank", Eigen::Vector3d(r, 0, 0)),
                                       Eigen::Vector3d::UnitZ(), q_of(crank_side), q_of(crank)));
    b->system.add_joint(fr::make_joint("wrist", fr::JointType::revolute, slider_end_marker,
                                       fr::point_marker(b->system.model(slider), slider, "slider", Eigen::Vector3d::Zero()),
                                       Eigen::Vector3d::UnitZ(), q_of(slider_side), q_of(slider)));
    b->system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute,
                                       fr::point_marker(b->system.model(crank), crank, "crank", Eigen::Vector3d::Zero()),
                                       fr::ground_marker(Eigen::Vector3d::Zero()), Eigen::Vector3d::UnitZ(), q_of(crank),
                                       Eigen::VectorXd(), angle));
    b->system.add_joint(fr::make_joint("guide", fr::JointType::prismatic,
                                       fr::point_marker(b->system.model(slider), slider, "slider", Eigen::Vector3d::Zero()),
                                       fr::point_marker(b->system.model(carriage), carriage, "carriage", Eigen::Vector3d::Zero()),
                                       Eigen::Vector3d::UnitX(), q_of(slider), q_of(carriage)));
    b->system.add_joint(fr::make_joint("rail", fr::JointType::prismatic,
                                       fr::point_marker(b->system.model(carriage), carriage, "carriage", Eigen::Vector3d::Zero()),
                                       fr::ground_marker(slider_state.position), Eigen::Vector3d::UnitZ(), q_of(carriage),
                                       Eigen::VectorXd()));
    return b;
  };
  return s;
}

// Scene 3: a free flexible plate spinning near its intermediate principal axis, no damping. An aluminium plate
// 0.4 x 0.3 x 0.004 m (E 70e9 Pa, ρ 2700 kg/m³; 20 x 15 x 1 cells, 672 nodes, 2016 DOFs), free-free modes,
// spinning at 30 rad/s about its intermediate axis y with a 1e-3 perturbation about x and z: it flips within 1 s.
// The spin is about 0.1 of the first elastic frequency. The flip amplifies every error exponentially, and the
// rotation-matrix coordinates of the GCMS and of the full-order reference integrate a 30 rad/s spin with a far larger
// error than Euler parameters do (docs/accuracy-and-speed.md), so the reference takes h = 1e-5 s.
Scene scene_plate(bool quick) {
  static const Part part = make_part({"aluminium", 70e9, 0.33, 2700.0}, 0.4, 0.3, 0.004, 20, 15, 1);
  static const flexbody::format::BodyData data = body_data(part, 32, {});
  Scene s;
  s.name = "plate";
  s.end = 1.0;
  s.sample = 0.01;
  s.steps = quick ? std::vector<double>{2e-3, 5e-4} : std::vector<double>{5e-3, 2.5e-3, 1.25e-3, 6.25e-4, 3.125e-4, 1.5625e-4};
  s.reference_step = quick ? 3.125e-4 : 1e-5;
  s.modes = quick ? std::vector<int>{2, 8} : std::vector<int>{2, 4, 8, 16, 32};
  s.kinds = {Kind::gcms, Kind::ffrf_mean_axis};
  s.tolerances = quick ? std::vector<double>{1e-6, 1e-8} : std::vector<double>{1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  s.build = [](Kind kind, int modes) {
    auto b = std::make_unique<Built>();
    fr::BodyState state;
    state.angular_velocity = Eigen::Vector3d(0.03, 30.0, 0.03);
    b->body = b->system.add_body("plate", model_of(part, &data, kind, modes), state);
    b->tip = fr::node_marker(b->system.model(b->body), b->body, "plate", nearest(part, {0.4, 0.3, 0.004}));
    return b;
  };
  return s;
}

// Ties the nodes `root` of body `body` (a full-order model) to points of the rigid body `hub` at the same places,
// one spherical joint each: the rbe2 interface of the reduced models.
void tie_root(Built& b, int hub, const Part& part, const std::vector<int>& root) {
  const Eigen::VectorXd q0 = b.system.initial_coordinates();
  const Eigen::VectorXd q_hub = b.system.body_coordinates(q0, hub), q_body = b.system.body_coordinates(q0, b.body);
  const Eigen::Matrix3d a = fr::orientation_of(q_hub);
  for (int i : root) {
    const fr::Marker node = fr::node_marker(b.system.model(b.body), b.body, "body", i);
    const Eigen::Vector3d at = fr::marker_position(node, q_body);
    b.system.add_joint(fr::make_joint("tie " + std::to_string(i), fr::JointType::spherical,
                                      fr::point_marker(b.system.model(hub), hub, "hub", a.transpose() * (at - q_hub.head<3>())),
                                      node, Eigen::Vector3d::UnitZ(), q_hub, q_body));
  }
  static_cast<void>(part);
}

// Scene 4: a blade spun up by a driven joint. An aluminium blade 0.5 x 0.05 x 0.005 m (E 70e9 Pa, ρ 2700 kg/m³; 25 x
// 4 x 1 cells, 260 nodes), Craig-Bampton with its root face an rbe2 interface fixed to a rigid hub (2 kg, gyration
// radius 0.05 m) at 0.05 m from the axis; the hub is driven about z from rest to Ω = 0.2 ω₁ (ω₁ the blade's first
// clamped frequency: 75 Hz with this mesh, whose single layer of elements locks in flapwise bending, so Ω = 94 rad/s)
// with φ̇ = Ω (1 − cos πt/T)/2 over T = 0.5 s, then at Ω to 0.75 s (8 turns), under gravity −z (the blade sags
// flapwise, and the spin-up bends it edgewise). Quantities: the blade tip's path and the driving torque (the driven
// joint's moment on the hub). Damped like the pendulum (β = 2e-5 s: 1 % near 160 Hz), for the same reason.
Scene scene_rotor(bool quick) {
  static const Part part = make_part({"aluminium", 70e9, 0.33, 2700.0}, 0.5, 0.05, 0.005, 25, 4, 1);
  static std::vector<int> root;
  if (root.empty())
    for (Eigen::Index i = 0; i < part.nodes.rows(); ++i)
      if (part.mesh.nodes(i, 0) == 0.0) root.push_back(static_cast<int>(i));
  static const flexbody::format::BodyData data = body_data(part, 32, root);
  static const double omega = 0.2 * 2.0 * 3.141592653589793 * data.modes.fixed_interface_frequencies_hz(0);
  std::printf("rotor: blade's first clamped frequency %.4g Hz, first modes %.4g, %.4g Hz; spin %.4g rad/s\n",
              data.modes.fixed_interface_frequencies_hz(0), data.modes.frequencies_hz(0), data.modes.frequencies_hz(1), omega);
  Scene s;
  s.name = "rotor";
  s.end = 0.75;
  s.sample = 0.01;
  s.steps = quick ? std::vector<double>{2e-3, 5e-4} : std::vector<double>{2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4};
  s.reference_step = quick ? 2.5e-4 : 3.125e-5;
  s.modes = quick ? std::vector<int>{2, 8} : std::vector<int>{2, 4, 8, 16, 32};
  s.kinds = {Kind::gcms, Kind::ffrf_mean_axis, Kind::ffrf_interface};
  s.tolerances = quick ? std::vector<double>{1e-6, 1e-8} : std::vector<double>{1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  s.build = [](Kind kind, int modes) {
    auto b = std::make_unique<Built>();
    Eigen::Vector3d center = Eigen::Vector3d::Zero();  // the root face's centre, body frame
    for (int i : root) center += part.nodes.row(i).transpose() / static_cast<double>(root.size());
    // The blade's root centre sits at (0.05, 0, 0); the axis is z through the origin, where the hub's centre is.
    fr::BodyState blade;
    blade.position = Eigen::Vector3d(0.05, 0.0, 0.0) - center;
    b->body = b->system.add_body("blade", model_of(part, &data, kind, modes, 2e-5), blade);
    const int hub = b->system.add_body("hub", hub_model(2.0, 0.05), fr::BodyState{});
    const fr::BodyModel& m = b->system.model(b->body);
    b->tip = fr::node_marker(m, b->body, "blade", nearest(part, {0.5, 0.025, 0.0025}));
    const Eigen::VectorXd q0 = b->system.initial_coordinates();
    const Eigen::VectorXd q_hub = b->system.body_coordinates(q0, hub);
    auto angle = [](double t) {
      constexpr double ramp = 0.5, pi = 3.141592653589793;
      if (t >= ramp) return omega * (t - 0.5 * ramp);
      return 0.5 * omega * (t - ramp / pi * std::sin(pi * t / ramp));
    };
    b->joint = 0;
    b->moment = true;
    b->system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute,
                                       fr::point_marker(b->system.model(hub), hub, "hub", Eigen::Vector3d::Zero()),
                                       fr::ground_marker(Eigen::Vector3d::Zero()), Eigen::Vector3d::UnitZ(), q_hub,
                                       Eigen::VectorXd(), angle));
    if (kind == Kind::full_order) {
      tie_root(*b, hub, part, root);
    } else {
      const fr::Marker r = fr::interface_marker(m, b->body, "blade", "root");
      const Eigen::VectorXd q_blade = b->system.body_coordinates(q0, b->body);
      b->system.add_joint(fr::make_joint("root", fr::JointType::fixed, r,
                                         fr::point_marker(b->system.model(hub), hub, "hub", fr::marker_position(r, q_blade)),
                                         Eigen::Vector3d::UnitZ(), q_blade, q_hub));
    }
    b->system.set_gravity(Eigen::Vector3d(0, 0, -9.81));
    return b;
  };
  return s;
}

}  // namespace work_precision
