// GeneralizedAlpha::save and restore (issue 32): a run continued from a checkpoint in a new integrator, on a new
// System built the same way (as fbsim --resume does in a new process), gives the same bits as the run that never
// stopped, whatever the Newton matrix kept then: random mechanisms of GCMS, FFRF and rigid bodies with driven joints,
// closed loops and springs; the reduced matrix dense and sparse (KLU's pivot history); the stabilised form's
// alternating and coupled steps and the index-3 form; the dense Newton matrix; a checkpoint after a shortened step.
#include "mechanism_helpers.hpp"

#include "flexbody/format/checkpoint_file.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace {

using namespace mechanisms;

struct Case {
  std::string name;
  unsigned seed;
  int bodies, loops;
  std::function<void(fr::GeneralizedAlphaOptions&)> options;
};

struct Result {
  Eigen::VectorXd q, v, lambda;
  long iterations = 0, matrices = 0;
};

Result result_of(const fr::GeneralizedAlpha& integrator) {
  return {integrator.coordinates(), integrator.velocities(), integrator.multipliers(), integrator.total_iterations(),
          integrator.factorizations()};
}

// `steps` steps of 1 ms (the `shortened`-th one to a time 0.4 ms short of its end, step_to), stopped after `stop`
// steps and continued in a new system and integrator from the checkpoint when stop < steps.
Result run(const Case& c, int steps, int stop, int shortened = -1) {
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  c.options(options);
  auto system = random_mechanism(c.seed, c.bodies, c.loops);
  auto integrator = std::make_unique<fr::GeneralizedAlpha>(*system, options);
  for (int k = 0; k < steps; ++k) {
    if (k == stop) {
      flexbody::format::CheckpointData checkpoint;
      integrator->save(checkpoint);
      integrator.reset();
      system = random_mechanism(c.seed, c.bodies, c.loops);
      integrator = std::make_unique<fr::GeneralizedAlpha>(*system, options);
      integrator->restore(checkpoint);
    }
    if (k == shortened) integrator->step_to(integrator->time() + 0.6e-3);
    else integrator->step();
  }
  return result_of(*integrator);
}

class IntegratorCheckpoint : public ::testing::TestWithParam<Case> {};

TEST_P(IntegratorCheckpoint, ContinuesBitForBit) {
  const Case& c = GetParam();
  const Result straight = run(c, 60, 60);
  for (const int stop : {1, 17, 33}) {
    const Result resumed = run(c, 60, stop);
    EXPECT_TRUE(resumed.q == straight.q) << "stopped after step " << stop << ": |dq| = "
                                         << (resumed.q - straight.q).cwiseAbs().maxCoeff();
    EXPECT_TRUE(resumed.v == straight.v) << "stopped after step " << stop;
    EXPECT_TRUE(resumed.lambda == straight.lambda) << "stopped after step " << stop;
    EXPECT_EQ(resumed.iterations, straight.iterations) << "stopped after step " << stop;
    EXPECT_EQ(resumed.matrices, straight.matrices) << "stopped after step " << stop;
  }
  // After step_to's shortened step the Newton solver is built for its size: the checkpoint keeps that.
  const Result shortened = run(c, 40, 40, 20);
  const Result resumed = run(c, 40, 21, 20);
  EXPECT_TRUE(resumed.q == shortened.q) << "|dq| = " << (resumed.q - shortened.q).cwiseAbs().maxCoeff();
  EXPECT_EQ(resumed.matrices, shortened.matrices);
}

void defaults(fr::GeneralizedAlphaOptions&) {}

INSTANTIATE_TEST_SUITE_P(
    Mechanisms, IntegratorCheckpoint,
    ::testing::Values(
        Case{"tree_dense_reduced", 3, 6, 0, defaults},
        Case{"loops_dense_reduced", 7, 8, 2, defaults},
        Case{"tree_sparse_reduced", 11, 9, 0, [](fr::GeneralizedAlphaOptions& o) { o.reduced_matrix = fr::ReducedMatrix::sparse; }},
        Case{"loops_sparse_coupled", 7, 8, 2,
             [](fr::GeneralizedAlphaOptions& o) {
               o.reduced_matrix = fr::ReducedMatrix::sparse;
               o.coupled_from_start = true;
             }},
        Case{"loops_dense_coupled", 7, 8, 2, [](fr::GeneralizedAlphaOptions& o) { o.coupled_from_start = true; }},
        Case{"index3", 3, 6, 0, [](fr::GeneralizedAlphaOptions& o) { o.constraints = fr::ConstraintForm::index3; }},
        Case{"dense_newton", 5, 4, 1, [](fr::GeneralizedAlphaOptions& o) { o.newton_matrix = fr::NewtonMatrix::dense; }}),
    [](const ::testing::TestParamInfo<Case>& param_info) { return param_info.param.name; });

TEST(IntegratorCheckpointRefusal, AnotherSystemOrStepIsRefused) {
  auto system = random_mechanism(3, 6, 0);
  fr::GeneralizedAlphaOptions options;
  fr::GeneralizedAlpha integrator(*system, options);
  integrator.step();
  flexbody::format::CheckpointData checkpoint;
  integrator.save(checkpoint);
  auto other = random_mechanism(3, 5, 0);
  fr::GeneralizedAlpha smaller(*other, options);
  EXPECT_THROW(smaller.restore(checkpoint), std::invalid_argument);
  options.step = 2e-3;
  fr::GeneralizedAlpha coarser(*system, options);
  try {
    coarser.restore(checkpoint);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("step 0.001 s"), std::string::npos) << e.what();
  }
  checkpoint.numbers.erase("integrator.a");
  fr::GeneralizedAlpha same(*system, fr::GeneralizedAlphaOptions{});
  try {
    same.restore(checkpoint);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "checkpoint: missing entry integrator.a");
  }
  // A checkpoint from before failed steps were halved (issue 47) says why it cannot continue.
  flexbody::format::CheckpointData old;
  integrator.save(old);
  old.numbers.erase("integrator.retries");
  try {
    same.restore(old);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("run the scene again from the start"), std::string::npos) << e.what();
  }
}

}  // namespace
