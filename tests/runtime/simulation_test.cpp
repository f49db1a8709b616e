// The run of a scene (flexbody::scene::Simulation, shared by fbsim and the Python package): the rows kept in memory are
// the CSV files' numbers, a run in pieces records what one run does, and a run is refused an end it has passed.
#include "fbsim_cli_helpers.hpp"

#include "flexbody/scene/scene.hpp"
#include "flexbody/scene/simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace fs = flexbody::scene;
using fbsim_cli::bar_folder;
using fbsim_cli::csv_numbers;
using fbsim_cli::write_text;

namespace {

// The issue's pendulum (fbsim_cli_helpers.hpp) for 0.02 s, rows every 20 steps, with its monitors.
fs::Scene pendulum_scene() {
  std::string scene = fbsim_cli::kIssueScene;
  scene.replace(scene.find("end: 2.0"), 8, "end: 0.02, output_every: 20");
  scene += "monitors: true\n";
  write_text(bar_folder() / "simulation.yaml", scene);
  return fs::read_scene(bar_folder() / "simulation.yaml");
}

}  // namespace

TEST(Simulation, RowsInMemoryAreTheCsvFilesNumbers) {
  const std::filesystem::path out = bar_folder() / "simulation_out";
  fs::Simulation simulation(pendulum_scene(), fs::OutputSinks{out, true});
  simulation.run(simulation.scene().end_time);
  const auto& tables = simulation.tables();
  ASSERT_EQ(tables.size(), 2u);  // tip, then the monitors
  EXPECT_EQ(tables[0].name, "tip");
  EXPECT_EQ(tables[0].columns, (std::vector<std::string>{"x [m]", "y [m]", "z [m]"}));
  EXPECT_EQ(tables[1].name, "monitors");
  for (const fs::OutputTable& table : tables) {
    const auto rows = csv_numbers(out / (table.name + ".csv"));
    ASSERT_EQ(rows.size(), 11u) << table.name;  // t = 0 and every 20 of the 200 steps
    ASSERT_EQ(table.times.size(), rows.size());
    ASSERT_EQ(table.values.size(), rows.size() * table.columns.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      EXPECT_EQ(table.times[k], rows[k][0]);  // 17 significant digits: the same doubles
      for (std::size_t c = 0; c < table.columns.size(); ++c)
        EXPECT_EQ(table.values[k * table.columns.size() + c], rows[k][c + 1]) << table.name << " row " << k;
    }
  }
  EXPECT_EQ(simulation.summary().steps, 200);
}

TEST(Simulation, ARunInPiecesRecordsWhatOneRunDoes) {
  fs::Simulation whole(pendulum_scene(), fs::OutputSinks{std::nullopt, true});
  whole.run(0.02);
  fs::Simulation pieces(pendulum_scene(), fs::OutputSinks{std::nullopt, true});
  pieces.run(0.01);
  pieces.run(0.01);  // there already: nothing to do
  EXPECT_EQ(pieces.summary().steps, 100);
  EXPECT_THROW(pieces.run(0.005), std::invalid_argument);  // behind
  for (int k = 0; k < 50; ++k) pieces.step();
  pieces.run(0.02);
  const fs::OutputTable& a = whole.tables()[0];
  const fs::OutputTable& b = pieces.tables()[0];
  ASSERT_EQ(a.times.size(), b.times.size());  // the counts of steps go on across the pieces
  for (std::size_t k = 0; k < a.times.size(); ++k) EXPECT_NEAR(a.times[k], b.times[k], 1e-15);
  // The end of a piece is a step_to whose size is h up to the rounding of the time (1e-19 s), so the pieces' motion
  // differs from the whole run's by round-off (measured 1.1e-16 m of a 1 m bar's tip).
  for (std::size_t k = 0; k < a.values.size(); ++k) EXPECT_NEAR(a.values[k], b.values[k], 1e-12);
  EXPECT_EQ(pieces.summary().steps, whole.summary().steps);
}

TEST(Simulation, ARunFarFromTimeZeroTakesItsWholeSteps) {
  // A state set at t = 1e6 s (a restart of a long run): the times carry a rounding of 8 ε 1e6 = 1.8e-9 s, far above a
  // millionth of the step; run(end) counts its steps with it (it took a spurious last step of a few ε, which
  // step_to refused).
  fs::Simulation simulation(pendulum_scene(), fs::OutputSinks{std::nullopt, true});
  flexbody::runtime::IntegratorState state = simulation.state();
  state.time = 1e6;
  simulation.set_state(state);
  simulation.run(1e6 + 0.005);
  EXPECT_EQ(simulation.summary().steps, 50);
  EXPECT_EQ(simulation.time(), 1e6 + 0.005);
  simulation.run(1e6 + 0.005);  // there already: nothing
  EXPECT_EQ(simulation.summary().steps, 50);
}
