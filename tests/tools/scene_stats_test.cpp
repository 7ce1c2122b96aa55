// The per-frame CSV of `simit run SCENE`: the documented columns come first in their places,
// then assembly_ms and solve_ms, which split the frame's ms (assembly_ms <= ms, and the two
// add up to it).
#include "scene_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(cell);
  return out;
}

TEST(SceneStats, CsvSplitsEachFrameIntoAssemblyAndSolve) {
  const fs::path dir =
      fs::temp_directory_path() / ("simit_scene_stats_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string src = SIMIT_SOURCE_DIR;
  // The fem example on the small bar of tests/data, with a loose CG so that it is quick.
  const fs::path scene = dir / "bar.toml";
  std::ofstream(scene) << "program = \"" << src << "/examples/fem/fem.sim\"\n"
                       << "init = \"init\"\nstep = \"step\"\nframes = 2\n"
                       << "[tensors]\ncg_tol = 1e-8\ncg_max = 20\n"
                       << "[sets.verts]\nmesh = \"" << src << "/tests/data/bar2k.node\"\n"
                       << "elements = \"vertices\"\n"
                       << "[sets.verts.fields]\nx = \"position\"\nv = [0.1, 0.0, 0.1]\n"
                       << "pinned = \"y < 1e-4\"\n"
                       << "[sets.tets]\nmesh = \"" << src << "/tests/data/bar2k.node\"\n"
                       << "elements = \"tets\"\n"
                       << "[output]\nfolder = \"" << (dir / "out").string() << "\"\n"
                       << "name = \"bar\"\npoints = \"verts\"\nposition = \"x\"\n"
                       << "csv = \"stats.csv\"\n";
  SceneOptions options;
  options.file = scene.string();
  std::ostringstream out, err;
  ASSERT_EQ(run_scene(options, out, err), 0) << err.str();

  std::ifstream csv(dir / "out" / "stats.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "frame,time,ms,cg_iterations,cg_residual,energy,assembly_ms,solve_ms");
  int rows = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> cells = split(line);
    ASSERT_EQ(cells.size(), 8u) << line;
    const double ms = std::stod(cells[2]), assembly = std::stod(cells[6]),
                 solve = std::stod(cells[7]);
    EXPECT_GT(assembly, 0.0) << line;  // fem maps four times per step
    EXPECT_LE(assembly, ms) << line;
    EXPECT_GE(solve, 0.0) << line;
    EXPECT_NEAR(assembly + solve, ms, 1e-9 * ms) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace simit::tools
