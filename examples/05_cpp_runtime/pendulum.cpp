// A flexible pendulum with the flexbody runtime's C++ API: load a body file, hang it from one of its
// interfaces on a revolute joint about z, let gravity swing it, and print where another interface goes.
//
//   pendulum BODY.fbh5 PIVOT_INTERFACE WATCHED_INTERFACE [MODES]
#include <flexbody/runtime/generalized_alpha.hpp>
#include <flexbody/runtime/scene_builder.hpp>
#include <flexbody/runtime/system.hpp>

#include <cstdio>
#include <exception>
#include <string>

namespace fr = flexbody::runtime;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: pendulum BODY.fbh5 PIVOT_INTERFACE WATCHED_INTERFACE [MODES]\n");
    return 2;
  }
  try {
    // 1. The body: the file's first MODES modes (all by default), placed where its CAD puts it (its input frame at
    //    the origin).
    fr::SceneBody spec;  // the body file's keys of a scene file's body (scene_body.hpp)
    spec.file = argv[1];
    if (argc > 4) spec.modes = std::stoi(argv[4]);
    fr::System system;
    fr::SceneBuilder scene(system);
    scene.add_body("body", spec);

    // 2. A revolute joint about z at the pivot interface, to ground where that interface is now; gravity.
    scene.add_joint("pivot", fr::JointType::revolute, scene.interface("body", argv[2]), {}, Eigen::Vector3d::UnitZ());
    const fr::Marker watched = scene.interface("body", argv[3]);
    const int body = scene.body("body");
    system.set_gravity(Eigen::Vector3d(0, -9.81, 0));

    // 3. Generalized-alpha, 1 ms steps for 0.5 s.
    fr::GeneralizedAlphaOptions options;
    options.rho_infinity = 0.9;
    options.step = 1e-3;
    fr::GeneralizedAlpha integrator(system, options);
    std::printf("t [s],x [m],y [m],z [m]\n");  // the path of the watched interface, every 10 steps
    for (int step = 1; step <= 500; ++step) {
      integrator.step();
      if (step % 10 == 0) {
        const Eigen::Vector3d r = fr::marker_position(watched, system.body_coordinates(integrator.coordinates(), body));
        std::printf("%.3f,%.7f,%.7f,%.7f\n", integrator.time(), r.x(), r.y(), r.z());
      }
    }
    const fr::Energies e = system.energies(integrator.coordinates(), integrator.velocities());
    std::printf("energy %.6g J after %ld Newton iterations\n", e.total(), integrator.total_iterations());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pendulum: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
