// The Newton iterations of generalized-α allocate no memory (issue 14: "no allocations per iteration", for the
// FFRF as for the GCMS): every joint type, applied forces, torques, a spring-damper, damping and gravity, on GCMS,
// FFRF and rigid bodies, in both constraint forms. This executable replaces malloc and realloc (glibc's
// __libc_malloc behind them; CMake builds it on glibc only) to count the calls made during steps that kept their
// Newton matrix; a step that builds one allocates (the factorization), and is not counted. The two bars carry
// geometric stiffness cases (made up), weighted at every iteration.
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "test_bodies.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdio>
#include <memory>

extern "C" void* __libc_malloc(std::size_t size);
extern "C" void* __libc_realloc(void* pointer, std::size_t size);
extern "C" void* __libc_calloc(std::size_t count, std::size_t size);

namespace {
bool counting = false;
long allocations = 0;
}  // namespace

extern "C" void* malloc(std::size_t size) {
  if (counting) ++allocations;
  return __libc_malloc(size);
}

// calloc too: GCC turns a malloc followed by a memset to zero into calloc, which hid the sparse constraint
// projection's per-solve allocation from this test while it counted malloc and realloc only.
extern "C" void* calloc(std::size_t count, std::size_t size) {
  if (counting) ++allocations;
  return __libc_calloc(count, size);
}

extern "C" void* realloc(void* pointer, std::size_t size) {
  if (counting) ++allocations;
  return __libc_realloc(pointer, size);
}

namespace fr = flexbody::runtime;

namespace {

// A soft bar 1 x 0.04 x 0.02 m (E 5e9 Pa, ρ 1000 kg/m³; 10 x 2 x 1 Kuhn-split cells), its first 4 free-free modes,
// with an interface "end" at the node nearest (−0.5, 0, 0) and made-up geometric stiffness cases (the six
// centrifugal ones and the end's six), so that the prestress weights and forces are counted too.
const flexbody::format::BodyData& bar() {
  static const flexbody::format::BodyData data = [] {
    flexbody::format::BodyData b = flexbody::test::soft_bar(1.0, 10, 4);
    Eigen::Index end = 0;
    (b.mesh.nodes.rowwise() - Eigen::RowVector3d(-0.5, 0, 0)).rowwise().squaredNorm().minCoeff(&end);
    const Eigen::Index n_f = b.gcms.fields.cols();
    flexbody::format::Interface i;
    i.name = "end";
    i.coupling = "rbe3";
    i.nodes = Eigen::VectorXi::Constant(1, static_cast<int>(end));
    i.weights = Eigen::VectorXd::Ones(1);
    i.reference_point = b.mesh.nodes.row(end).transpose();
    i.y_row = Eigen::VectorXd(4 + n_f);
    i.y_row << 1.0, b.mesh.nodes.row(end).transpose(), b.gcms.fields.row(end).transpose();
    i.rotation = Eigen::MatrixXd::Zero(3, 3 * n_f);
    b.interfaces.push_back(i);
    std::srand(29);
    for (const char* source : {"centrifugal", "end"})
      for (int k = 0; k < 6; ++k) {
        b.geometric_stiffness.cases.push_back(std::string(source) + ":" +
                                              (std::string(source) == "end" ? flexbody::format::kInterfaceLoadCases[k]
                                                                            : flexbody::format::kCentrifugalCases[k]));
        Eigen::MatrixXd g = Eigen::MatrixXd::Zero(4 + n_f, 4 + n_f);
        const Eigen::MatrixXd r = Eigen::MatrixXd::Random(3 + n_f, 3 + n_f);
        g.bottomRightCorner(3 + n_f, 3 + n_f) = 1e-3 * r * r.transpose();
        b.geometric_stiffness.matrices.push_back(g);
      }
    return b;
  }();
  return data;
}

fr::BodyModel box(double mass, double radius) {
  return fr::rigid_body_model(mass, Eigen::Matrix3d::Identity() * mass * radius * radius, "box");
}

Eigen::Index nearest(const fr::BodyModel& model, const Eigen::Vector3d& point) {
  Eigen::Index k = 0;
  (model.nodes.rowwise() - point.transpose()).rowwise().squaredNorm().minCoeff(&k);
  return k;
}

// A GCMS bar (Rayleigh damped; a force and a torque at its middle) pinned to ground at one end; an FFRF bar (a
// force and a torque) on a spherical joint at its other end; a rigid box welded (fixed joint) to the FFRF bar's far
// end; a rigid slider on a prismatic joint along a rigid base welded to ground; a second, free GCMS bar tied to the
// slider by a spring-damper (markers on bodies of 12 and 3 (4 + n_f) coordinates); a rigid crank on a driven
// revolute joint. Gravity.
std::unique_ptr<fr::System> scene() {
  auto s = std::make_unique<fr::System>();
  fr::System& system = *s;
  fr::BodyModel gcms = fr::make_body_model(bar(), std::nullopt, "gcms bar");
  gcms.damping = fr::rayleigh_damping(gcms, 0.0, 1e-4);
  fr::BodyModel ffrf = fr::make_body_model(bar(), std::nullopt, "ffrf bar");
  ffrf.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(ffrf, fr::FloatingFrame::mean_axis));
  fr::BodyState first, second, welded, base, slider, free_bar, crank;
  second.position = Eigen::Vector3d(1.0, 0, 0);
  welded.position = Eigen::Vector3d(1.55, 0, 0);
  base.position = Eigen::Vector3d(1.55, -0.5, 0);
  slider.position = Eigen::Vector3d(1.55, -0.5, 0.1);
  free_bar.position = Eigen::Vector3d(1.55, -1.0, 0.1);
  crank.position = Eigen::Vector3d(0, 1, 0);
  const int b0 = system.add_body("gcms bar", gcms, first), b1 = system.add_body("ffrf bar", ffrf, second);
  const int b2 = system.add_body("box", box(0.2, 0.02), welded), b3 = system.add_body("base", box(1.0, 0.05), base);
  const int b4 = system.add_body("slider", box(0.1, 0.02), slider), b5 = system.add_body("free bar", gcms, free_bar);
  const int b6 = system.add_body("crank", box(0.5, 0.05), crank);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  auto q_of = [&](int b) { return system.body_coordinates(q0, b); };
  auto point = [&](int b, const Eigen::Vector3d& x) { return fr::point_marker(system.model(b), b, "body", x); };
  const fr::BodyModel &m0 = system.model(b0), &m1 = system.model(b1);
  const fr::Marker root = fr::interface_marker(m0, b0, "gcms bar", "end");  // prestressed by the pin's reaction
  const fr::Marker tip = fr::node_marker(m0, b0, "gcms bar", nearest(m0, {0.5, 0, 0}));
  const fr::Marker near = fr::interface_marker(m1, b1, "ffrf bar", "end");
  const fr::Marker far = fr::node_marker(m1, b1, "ffrf bar", nearest(m1, {0.5, 0, 0}));
  system.add_joint(fr::make_joint("pin", fr::JointType::revolute, root, fr::ground_marker(fr::marker_position(root, q_of(b0))),
                                  Eigen::Vector3d::UnitZ(), q_of(b0), Eigen::VectorXd()));
  // The FFRF bar's near node starts at the GCMS bar's tip node (the same mesh, shifted by 1 m).
  system.add_joint(fr::make_joint("ball", fr::JointType::spherical, near, tip, Eigen::Vector3d::UnitZ(), q_of(b1), q_of(b0)));
  system.add_joint(fr::make_joint("weld", fr::JointType::fixed, far, point(b2, fr::marker_position(far, q_of(b1)) - welded.position),
                                  Eigen::Vector3d::UnitZ(), q_of(b1), q_of(b2)));
  system.add_joint(fr::make_joint("ground", fr::JointType::fixed, point(b3, Eigen::Vector3d::Zero()), fr::ground_marker(base.position),
                                  Eigen::Vector3d::UnitZ(), q_of(b3), Eigen::VectorXd()));
  system.add_joint(fr::make_joint("rail", fr::JointType::prismatic, point(b4, Eigen::Vector3d::Zero()), point(b3, Eigen::Vector3d::Zero()),
                                  Eigen::Vector3d::UnitX(), q_of(b4), q_of(b3)));
  system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute, point(b6, Eigen::Vector3d::Zero()),
                                  fr::ground_marker(crank.position), Eigen::Vector3d::UnitZ(), q_of(b6), Eigen::VectorXd(),
                                  [](double t) { return 3.0 * t * t; }));
  system.add_force({fr::point_marker(m0, b0, "gcms bar", Eigen::Vector3d::Zero()), [](double t) { return Eigen::Vector3d(0, 1.0 + t, 0); }});
  system.add_torque({fr::point_marker(m0, b0, "gcms bar", Eigen::Vector3d::Zero()), [](double) { return Eigen::Vector3d(0.1, 0, 0.2); }});
  system.add_force({fr::point_marker(m1, b1, "ffrf bar", Eigen::Vector3d(0.2, 0, 0)), [](double) { return Eigen::Vector3d(0, 0, 0.5); }});
  system.add_torque({fr::point_marker(m1, b1, "ffrf bar", Eigen::Vector3d::Zero()), [](double) { return Eigen::Vector3d(0, 0, 0.5); }});
  const fr::BodyModel& m5 = system.model(b5);
  system.add_spring({"spring", point(b4, Eigen::Vector3d::Zero()), fr::node_marker(m5, b5, "free bar", nearest(m5, {0.5, 0, 0})),
                     50.0, 0.5, 0.3});
  system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
  return s;
}

struct Count {
  long allocations = 0;  ///< in steps that kept their Newton matrix
  int kept = 0;          ///< such steps
};

Count count(fr::ConstraintForm form) {
  const auto system = scene();
  fr::GeneralizedAlphaOptions options;
  options.step = 2e-4;
  options.constraints = form;
  fr::GeneralizedAlpha integrator(*system, options);
  for (int i = 0; i < 10; ++i) integrator.step();  // first sizes of every work vector
  Count c;
  for (int i = 0; i < 100; ++i) {
    const long built = integrator.factorizations();
    allocations = 0;
    counting = true;
    integrator.step();
    counting = false;
    if (integrator.factorizations() != built) continue;
    ++c.kept;
    c.allocations += allocations;
  }
  // The two bars' geometric stiffness was weighted (the pin's and the ball's reactions, the spin).
  for (int b : {0, 1}) EXPECT_GT(system->prestress_weights(b).cwiseAbs().maxCoeff(), 0.0) << b;
  return c;
}

}  // namespace

// Measured before this test: 294 allocations per step of two GCMS bars on revolute joints (joint evaluations, the
// elastic forces, Φ_qᵀ μ, the constant core's solve), 2 per step of FFRF bars (the deformation check). The constant
// core only: the dense Newton solve (the reference) allocates its right-hand side.
TEST(Allocations, NewtonIterationsAllocateNothing) {
  for (const fr::ConstraintForm form : {fr::ConstraintForm::stabilized_index2, fr::ConstraintForm::index3}) {
    const Count c = count(form);
    std::printf("%s: %ld allocations in %d steps that kept their Newton matrix\n",
                form == fr::ConstraintForm::index3 ? "index-3" : "stabilised index-2", c.allocations, c.kept);
    EXPECT_GE(c.kept, 50);  // the check is not empty
    EXPECT_EQ(c.allocations, 0);
  }
}
