// Checkpoints and resume (issue 32): a run stopped, checkpointed and continued in a new Simulation (a new scene read
// from the same files, as fbsim --resume does in a new process) writes the uninterrupted run's files byte for byte:
// GCMS, FFRF and a rigid body with a driven joint, rows every n steps and by time, ParaView frames; a checkpoint of
// another scene, another body file, or a directory that does not match it is refused in one line.
#include "fbsim_cli_helpers.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/format/checkpoint_file.hpp"
#include "flexbody/scene/scene.hpp"
#include "flexbody/scene/simulation.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace fs = flexbody::scene;
using fbsim_cli::bar_folder;
using fbsim_cli::write_text;

namespace {

std::string bytes_of(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every file under `directory` but the checkpoint, by its path relative to it.
std::map<std::string, std::string> files_under(const std::filesystem::path& directory) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(directory))
    if (entry.is_regular_file() && entry.path().filename() != fs::kCheckpointFileName)
      files[std::filesystem::relative(entry.path(), directory).string()] = bytes_of(entry.path());
  return files;
}

// The bar of fbsim_cli_helpers.hpp swinging from its root: GCMS with 8 modes, FFRF with 8 modes in its root's frame,
// or rigid and driven about z at 3 rad/s (ramped over 0.01 s); 0.03 s in steps of 1e-4 s (300), rows every 7 steps or
// every 0.0013 s, monitors, and ParaView frames every 0.004 s.
std::string scene_text(const std::string& kind, bool by_time) {
  std::string body = "bar: {file: bar.fbh5, modes: 8}";
  std::string joint = "pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}";
  if (kind == "ffrf") body = "bar: {file: bar.fbh5, modes: 8, formulation: ffrf, frame: {interface: root}}";
  if (kind == "rigid") {
    body = "bar: {file: bar.fbh5, modes: rigid}";
    joint = "pivot: {type: driven-revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1], speed: 3, ramp: 0.01}";
  }
  // step: auto (error control): the GCMS bar, its steps chosen to keep 1e-9 m per step.
  const std::string step = kind == "auto" ? "step: auto, error_tolerance: 1.0e-9" : "step: 1.0e-4";
  return "bodies:\n  " + body + "\njoints:\n  " + joint +
         "\ngravity: [0, -9.81, 0]\nintegrator: {type: generalized-alpha, rho_inf: 0.9, " + step + ", end: 0.03, " +
         (by_time ? "output_interval: 0.0013}" : "output_every: 7}") +
         "\noutputs:\n  tip: {body: bar, interface: tip, quantities: [position, velocity]}\n"
         "  pivot: {joint: pivot, quantities: [reaction_force]}\nmonitors: true\n"
         "paraview: {bodies: [bar], interval: 0.004, stresses: false}\n";
}

fs::Scene scene_of(const std::string& kind, bool by_time) {
  const std::filesystem::path file = bar_folder() / ("checkpoint_" + kind + ".yaml");
  write_text(file, scene_text(kind, by_time));
  return fs::read_scene(file);
}

// The run of `kind` into `out`, stopped after `stop` steps (none when 0), checkpointed, and continued by a new
// Simulation; returns the steps it counted in all.
long run(const std::string& kind, bool by_time, const std::filesystem::path& out, int stop) {
  std::filesystem::remove_all(out);
  long steps = 0;
  {
    fs::Simulation simulation(scene_of(kind, by_time), fs::OutputSinks{out, false});
    int taken = 0;
    const bool ended = simulation.run(0.03, {}, [&taken, stop] { return stop > 0 && ++taken == stop; });
    EXPECT_EQ(ended, stop == 0);
    if (ended) return simulation.summary().steps;
    simulation.checkpoint();
    EXPECT_EQ(simulation.last_checkpoint(), simulation.time());
  }
  fs::Simulation resumed(scene_of(kind, by_time), fs::OutputSinks{out, false}, fs::Resume{out / fs::kCheckpointFileName});
  EXPECT_TRUE(resumed.run(0.03));
  steps = resumed.summary().steps;
  return steps;
}

class SimulationCheckpoint : public ::testing::TestWithParam<std::tuple<std::string, bool>> {};

TEST_P(SimulationCheckpoint, AResumedRunWritesTheUninterruptedRunsFiles) {
  const auto& [kind, by_time] = GetParam();
  const std::filesystem::path whole = bar_folder() / ("ck_whole_" + kind), part = bar_folder() / ("ck_part_" + kind);
  EXPECT_EQ(run(kind, by_time, whole, 0), 300);
  const auto expected = files_under(whole);
  EXPECT_EQ(expected.size(), 3u + 1u + 9u);  // tip, pivot, monitors; bar.pvd; frames at 0, 4, ..., 28 ms and the end
  // Stopped after a row (step 7), between rows, and just before a frame (step 120: 12 ms).
  for (const int stop : {7, 38, 119}) {
    SCOPED_TRACE("stopped after step " + std::to_string(stop));
    EXPECT_EQ(run(kind, by_time, part, stop), 300);
    const auto resumed = files_under(part);
    ASSERT_EQ(resumed.size(), expected.size());
    for (const auto& [name, bytes] : expected) EXPECT_TRUE(resumed.at(name) == bytes) << name << " differs";
  }
}

INSTANTIATE_TEST_SUITE_P(Bodies, SimulationCheckpoint,
                         ::testing::Combine(::testing::Values("gcms", "ffrf", "rigid"), ::testing::Bool()),
                         [](const auto& param_info) {
                           return std::get<0>(param_info.param) + (std::get<1>(param_info.param) ? "_by_time" : "_by_steps");
                         });

// Under error control the resumed run takes the steps the uninterrupted one took (the controller's state, which
// vibrations its estimate counts, and a_{n−1} are in the checkpoint) and writes its files byte for byte.
TEST(SimulationCheckpoint, AResumedRunUnderErrorControlWritesTheUninterruptedRunsFiles) {
  const std::filesystem::path whole = bar_folder() / "ck_whole_auto", part = bar_folder() / "ck_part_auto";
  const long steps = run("auto", true, whole, 0);
  EXPECT_GT(steps, 20);
  const auto expected = files_under(whole);
  for (const int stop : {3, 11, static_cast<int>(steps) - 2}) {
    SCOPED_TRACE("stopped after step " + std::to_string(stop));
    EXPECT_EQ(run("auto", true, part, stop), steps);
    const auto resumed = files_under(part);
    ASSERT_EQ(resumed.size(), expected.size());
    for (const auto& [name, bytes] : expected) EXPECT_TRUE(resumed.at(name) == bytes) << name << " differs";
  }
}

// A checkpoint written by the pendulum after 50 steps, in `out`.
std::filesystem::path stopped_run(const std::filesystem::path& out) {
  std::filesystem::remove_all(out);
  fs::Simulation simulation(scene_of("gcms", false), fs::OutputSinks{out, false});
  int taken = 0;
  EXPECT_FALSE(simulation.run(0.03, {}, [&taken] { return ++taken == 50; }));
  return simulation.checkpoint();
}

std::string refusal(fs::Scene scene, const std::filesystem::path& out) {
  try {
    fs::Simulation resumed(std::move(scene), fs::OutputSinks{out, false}, fs::Resume{out / fs::kCheckpointFileName});
  } catch (const std::exception& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  return "accepted";
}

TEST(SimulationCheckpointRefusal, AnotherSceneIsRefused) {
  const std::filesystem::path out = bar_folder() / "ck_refused";
  stopped_run(out);
  // One more character in the scene file (a comment): another scene.
  const std::filesystem::path file = bar_folder() / "checkpoint_edited.yaml";
  write_text(file, scene_text("gcms", false) + "# edited\n");
  EXPECT_NE(refusal(fs::read_scene(file), out).find("written for another scene"), std::string::npos)
      << refusal(fs::read_scene(file), out);
  // The same scene, another step.
  std::string step = scene_text("gcms", false);
  step.replace(step.find("step: 1.0e-4"), 12, "step: 2.0e-4");
  write_text(file, step);
  EXPECT_NE(refusal(fs::read_scene(file), out).find("written for another scene"), std::string::npos);
}

TEST(SimulationCheckpointRefusal, AnotherBodyFileIsRefused) {
  // The scene in a folder of its own, with a copy of the bar that is then replaced by the bar with 6 modes.
  const std::filesystem::path folder = bar_folder() / "ck_body";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  std::filesystem::copy_file(bar_folder() / "bar.fbh5", folder / "bar.fbh5");
  write_text(folder / "scene.yaml", scene_text("gcms", false));
  const std::filesystem::path out = folder / "out";
  {
    fs::Simulation simulation(fs::read_scene(folder / "scene.yaml"), fs::OutputSinks{out, false});
    int taken = 0;
    EXPECT_FALSE(simulation.run(0.03, {}, [&taken] { return ++taken == 20; }));
    simulation.checkpoint();
  }
  flexbody::format::BodyData other = flexbody::format::read_body_file(folder / "bar.fbh5");
  other.provenance.created_utc = "2000-01-01T00:00:00Z";  // the same numbers, another file
  flexbody::format::write_body_file(other, folder / "bar.fbh5");
  const std::string why = refusal(fs::read_scene(folder / "scene.yaml"), out);
  EXPECT_NE(why.find("written with another body file: " + (folder / "bar.fbh5").string()), std::string::npos) << why;
}

TEST(SimulationCheckpointRefusal, ADirectoryThatDoesNotMatchIsRefused) {
  const std::filesystem::path out = bar_folder() / "ck_directory";
  stopped_run(out);
  // A CSV file cut shorter than at the checkpoint.
  std::filesystem::resize_file(out / "tip.csv", 10);
  std::string why = refusal(scene_of("gcms", false), out);
  EXPECT_NE(why.find("tip.csv: has 10 bytes, fewer than"), std::string::npos) << why;
  // A frame gone, in a directory whose CSV files ran on after the checkpoint: refused before anything is changed.
  stopped_run(out);
  {
    fs::Simulation on(scene_of("gcms", false), fs::OutputSinks{out, false}, fs::Resume{out / fs::kCheckpointFileName});
    on.run(0.03);
  }
  const std::string tip = bytes_of(out / "tip.csv");
  std::filesystem::remove(out / "bar" / "bar_000001.vtu");
  why = refusal(scene_of("gcms", false), out);
  EXPECT_NE(why.find("bar_000001.vtu: a frame of the checkpoint's series is missing"), std::string::npos) << why;
  EXPECT_EQ(bytes_of(out / "tip.csv"), tip);
  // Written by another fbsim (a build whose numbers may differ).
  stopped_run(out);
  flexbody::format::CheckpointData foreign = flexbody::format::read_checkpoint_file(out / fs::kCheckpointFileName);
  foreign.texts["identity.program"] = "fbsim 0.0.1";
  flexbody::format::write_checkpoint_file(foreign, out / fs::kCheckpointFileName);
  why = refusal(scene_of("gcms", false), out);
  EXPECT_NE(why.find("written by fbsim 0.0.1, this is fbsim "), std::string::npos) << why;
  // A damaged checkpoint: one byte changed.
  stopped_run(out);
  std::string bytes = bytes_of(out / fs::kCheckpointFileName);
  bytes[bytes.size() - 40] = static_cast<char>(bytes[bytes.size() - 40] ^ 0x10);
  std::ofstream(out / fs::kCheckpointFileName, std::ios::binary | std::ios::trunc) << bytes;
  why = refusal(scene_of("gcms", false), out);
  EXPECT_NE(why.find("damaged or modified after it was written"), std::string::npos) << why;
}

TEST(SimulationCheckpointRefusal, AFreshRunRemovesAnOldCheckpoint) {
  const std::filesystem::path out = bar_folder() / "ck_fresh";
  stopped_run(out);
  ASSERT_TRUE(std::filesystem::exists(out / fs::kCheckpointFileName));
  fs::Simulation fresh(scene_of("gcms", false), fs::OutputSinks{out, false});
  EXPECT_FALSE(std::filesystem::exists(out / fs::kCheckpointFileName));  // it would not match the files rewritten now
}

}  // namespace
