// `simit run` on a scene whose mesh the scene renumbers: a solver's message names the vertex
// by its number in the mesh file (and its set), not by the row it has after renumbering; with
// `reorder = false` the plain row numbers stay. Both executors say the same.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
#include "simit/executor.h"

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

// A chain of 7 vertices on the moment curve (t, t^2, t^3), t = c / 3 for chain vertex c, and
// the 4 tets (c, c+1, c+2, c+3) along it. The file lists the chain out of order: its vertex f
// is chain vertex kOrder[f], so that renumbering for locality (along the chain) moves them.
// File vertex 0 is chain vertex 3, the middle one, at x = 1: no renumbering along the chain
// keeps it first.
constexpr int kOrder[7] = {3, 0, 5, 1, 6, 2, 4};

const char* kProgram = R"(
element Vertex
  x : vector[3](float);
  z : float;
  s : float;
  w : float;
end
element Tet
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);

% Diagonal, zero at the vertex marked z = 1 (the mesh's vertex 0).
func diagonal(t : Tet, v : (Vertex * 4)) -> L : matrix[verts,verts](float)
  for i in 0:4
    L(v(i), v(i)) = 1.0 - v(i).z;
  end
end

export func lower()
  L = map diagonal to tets reduce +;
  verts.s = triangularSolve(L, verts.z);
end

% As diagonal, zero there from the second call on (after bump): a compiled map's second call
% assembles on its specialised pattern, which must keep the mesh numbers too.
func diagonal_later(t : Tet, v : (Vertex * 4)) -> L : matrix[verts,verts](float)
  for i in 0:4
    L(v(i), v(i)) = 1.0 - v(i).z * v(i).w;
  end
end

func bump(inout v : Vertex)
  v.w = 1.0;
end

export func lower_later()
  L = map diagonal_later to tets reduce +;
  verts.s = triangularSolve(L, verts.z);
  apply bump to verts;
end

export func backslash()
  L = map diagonal to tets reduce +;
  verts.s = L \ verts.z;
end
)";

class MeshNumbers : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-mesh-numbers-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    int file_of[7];
    std::ostringstream node, ele;
    node << "7 3 0 0\n";
    for (int f = 0; f < 7; ++f) {
      const double t = kOrder[f] / 3.0;
      char line[128];
      std::snprintf(line, sizeof line, "%d %.17g %.17g %.17g\n", f, t, t * t, t * t * t);
      node << line;
      file_of[kOrder[f]] = f;
    }
    ele << "4 4 0\n";
    for (int c = 0; c < 4; ++c)
      ele << c << " " << file_of[c] << " " << file_of[c + 1] << " " << file_of[c + 2] << " "
          << file_of[c + 3] << "\n";
    std::ofstream(dir_ / "chain.node") << node.str();
    std::ofstream(dir_ / "chain.ele") << ele.str();
    std::ofstream(dir_ / "chain.sim") << kProgram;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Runs the scene with `step` (renumbered unless `reorder` is false); its stderr, after
  // checking that it failed.
  std::string run(const std::string& step, bool reorder, std::vector<std::string> extra = {}) {
    std::ofstream(dir_ / "scene.toml")
        << "program = \"chain.sim\"\nstep = \"" << step << "\"\nframes = 1\n"
        << (reorder ? "" : "reorder = false\n")
        << "[sets.verts]\nmesh = \"chain.node\"\nelements = \"vertices\"\n"
           "[sets.verts.fields]\nx = \"position\"\nz = \"x > 0.9 and x < 1.1\"\n"
           "[sets.tets]\nmesh = \"chain.node\"\nelements = \"tets\"\n";
    const std::string scene = (dir_ / "scene.toml").string();
    std::vector<std::string> args = {"simit", "run", scene};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    std::ostringstream out, err;
    EXPECT_EQ(run_cli(static_cast<int>(argv.size()), argv.data(), out, err), 1) << err.str();
    out_ = out.str();
    return err.str();
  }

  fs::path dir_;
  std::string out_;  // the last run's stdout
};

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_F(MeshNumbers, TriangularSolveNamesTheMeshVertex) {
  const std::string renumbered = run("lower", true);
  EXPECT_TRUE(
      has(renumbered,
          "triangularSolve: the diagonal entry of the row of element 0 of set 'verts' is zero"))
      << renumbered;
  const std::string plain = run("lower", false);
  EXPECT_TRUE(has(plain, "triangularSolve: the diagonal entry of row 0 is zero")) << plain;
  if (!simit::jit_available()) GTEST_SKIP() << "the JIT's half: this build has no JIT";
  const std::string jit =
      run("lower", true, {"--executor", "jit", "--jit-threshold", "0", "--jit-cache", "off"});
  EXPECT_EQ(jit, renumbered);
}

TEST_F(MeshNumbers, ASpecialisedPatternKeepsTheMeshNumbers) {
  const std::vector<std::string> two = {"--frames", "2"};
  const std::string renumbered = run("lower_later", true, two);
  EXPECT_TRUE(
      has(renumbered,
          "triangularSolve: the diagonal entry of the row of element 0 of set 'verts' is zero"))
      << renumbered;
  if (!simit::jit_available()) GTEST_SKIP() << "the JIT's half: this build has no JIT";
  const std::string jit = run("lower_later", true,
                              {"--frames", "2", "--executor", "jit", "--jit-threshold", "0",
                               "--jit-cache", "off", "--jit-stats"});
  // The second call ran on the specialised pattern (--jit-stats, on stdout).
  EXPECT_TRUE(has(out_ + jit, "specialised to")) << out_ << jit;
  EXPECT_TRUE(has(
      jit, "triangularSolve: the diagonal entry of the row of element 0 of set 'verts' is zero"))
      << jit;
}

TEST_F(MeshNumbers, SingularSolveNamesTheMeshVertex) {
  // Symmetric: Cholesky first, then LU, whose message is the one reported.
  const std::string renumbered = run("backslash", true);
  EXPECT_TRUE(has(renumbered,
                  "LU factorisation failed: the matrix is singular (the column of element 0 of "
                  "set 'verts' has no nonzero entry)"))
      << renumbered;
  if (!simit::jit_available()) GTEST_SKIP() << "the JIT's half: this build has no JIT";
  const std::string jit =
      run("backslash", true, {"--executor", "jit", "--jit-threshold", "0", "--jit-cache", "off"});
  EXPECT_EQ(jit, renumbered);
}

}  // namespace
}  // namespace simit::tools
