// The SIMD report of --jit-stats (docs/jit.md, "What vectorises"): what LLVM's loop
// vectoriser did with each compiled loop, a map kernel's lanes or why it has none, and the
// report of a kernel from the kernel cache. Programs run through the engine; the report's
// per-loop lines are read from the optimised module's dump (--dump=llvm).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"
#include "jit/ir_build.h"
#include "jit/kernel_cache.h"
#include "jit/loop_ir.h"
#include "jit/target.h"
#include "jit/tunables.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;

namespace fs = std::filesystem;

// Large enough that every pass runs many vectors' worth of components.
constexpr int kPoints = 4099;

const char* const kProgram = R"(element Point
  b : float;
  c : float;
end
extern points : set{Point};

func twice(p : Point) -> D : matrix[points,points](float)
  D(p, p) = 2.0 * p.b;
end

func flip(p : Point) -> D : matrix[points,points](float)
  var v = p.b;
  if p.c > 0.5
    v = -v;
  end
  D(p, p) = v;
end

export func pass() -> y : vector[points](float)
  y = 2.0 * points.b + points.c;
end

export func inner() -> s : float
  s = points.b' * points.c;
end

export func magnitude() -> s : float
  s = norm(points.b);
end

export func lanes() -> D : matrix[points,points](float)
  D = map twice to points reduce +;
end

export func branches() -> D : matrix[points,points](float)
  D = map flip to points reduce +;
end
)";

// The line of `text` holding `what` (from 1).
int line_of(const std::string& text, const std::string& what) {
  const size_t at = text.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
}

struct SimdRun {
  std::string stats, dump;
};

// Calls `function` twice (so that its statements and maps compile) and returns the stats and,
// with `dump`, the optimised modules. `cache`: the kernel cache folder, or "off".
SimdRun run(const std::string& function, bool dump, const std::string& cache = "off") {
  auto compiled = CompiledProgram::from_source("simd.sim", kProgram);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  points.add_many(kPoints);
  points.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  points.add_field("c", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < kPoints; ++i) {
    points.field(0).at<double>(i)[0] = 0.5 + 0.001 * i;
    points.field(1).at<double>(i)[0] = (i % 7) / 7.0;
  }
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.executor.jit_cache = cache;
  std::ostringstream dump_text;
  if (dump) {
    o.dump = &dump_text;
    o.executor.dump_llvm = true;
  }
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  for (int call = 0; call < 2; ++call) engine.call(*compiled->find_func(function), {});
  std::ostringstream os;
  engine.print_jit_stats(os);
  return {os.str(), dump_text.str()};
}

// The key line (which carries the notes) of the trace whose site line starts with `site`.
std::string key_line(const std::string& stats, const std::string& site) {
  const size_t at = stats.find("  " + site);
  if (at == std::string::npos) return "";
  const size_t key = stats.find('\n', at) + 1;
  return stats.substr(key, stats.find('\n', key) - key);
}

// The SIMD note of a key line, up to the next note (its own parts follow "; " too).
std::string simd_note(const std::string& key) {
  const size_t at = key.find("SIMD: ");
  if (at == std::string::npos) return "";
  size_t end = at;
  while ((end = key.find("; ", end + 1)) != std::string::npos) {
    const std::string next = key.substr(end + 2);
    const bool part = next.rfind("not: ", 0) == 0 || next.rfind("SLP: ", 0) == 0 ||
                      next.rfind("LLVM's vectorisers", 0) == 0 ||
                      next.rfind("no loop for", 0) == 0 || std::isdigit(next[0]);
    if (!part) break;
  }
  return key.substr(at, end == std::string::npos ? std::string::npos : end - at);
}

// The dump's per-loop lines: "; loop N (what): ...".
std::vector<std::string> loop_lines(const std::string& dump) {
  std::vector<std::string> out;
  std::istringstream in(dump);
  for (std::string l; std::getline(in, l);)
    if (l.rfind("; loop ", 0) == 0) out.push_back(l);
  return out;
}

// "N of M loops vectorised" (after "SIMD: ", or after a map's "no lanes (...); "): N and M,
// or -1s.
std::pair<int, int> vectorised(const std::string& note) {
  int n = -1, m = -1;
  size_t at = note.find("SIMD: ");
  if (at == std::string::npos) return {-1, -1};
  at += 6;
  if (note.compare(at, 9, "no lanes ") == 0) at = note.find("); ", at) + 3;
  if (std::sscanf(note.c_str() + at, "%d of %d", &n, &m) != 2) return {-1, -1};
  return {n, m};
}

bool jit() { return api::jit_available(); }

TEST(SimdReport, AnElementWisePassOverALargeVectorVectorises) {
  if (!jit()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const SimdRun r = run("pass", true);
  const std::string site =
      "statement (line " + std::to_string(line_of(kProgram, "y = 2.0 *")) + ")";
  const std::string key = key_line(r.stats, site);
  ASSERT_NE(key, "") << r.stats;
  // One pass, one loop, vectorised (four doubles on a host with AVX, two with SSE only).
  const auto [n, m] = vectorised(key);
  EXPECT_EQ(n, 1) << key;
  EXPECT_EQ(m, 1) << key;
  EXPECT_NE(key.find("loop vectorised (width "), std::string::npos) << key;
  EXPECT_EQ(key.find("not:"), std::string::npos) << key;
  const std::vector<std::string> loops = loop_lines(r.dump);
  ASSERT_EQ(loops.size(), 1u) << r.dump;
  EXPECT_NE(loops[0].find("(vector pass): vectorised, width "), std::string::npos) << loops[0];
}

// A dot product and a norm: each chunk's lanes are summed four at a time in vectors the
// emitter writes, and the chunks' partial sums are added in chunk order, a reduction LLVM may
// not reorder (docs/arithmetic.md): reported as such, not as a failure.
TEST(SimdReport, ADotProductAndANormReportTheContractsOrder) {
  if (!jit()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (const char* function : {"inner", "magnitude"}) {
    SCOPED_TRACE(function);
    const SimdRun r = run(function, true);
    const std::string line = function == std::string("inner") ? "s = points.b'" : "s = norm(";
    const std::string key =
        key_line(r.stats, "statement (line " + std::to_string(line_of(kProgram, line)) + ")");
    ASSERT_NE(key, "") << r.stats;
    EXPECT_NE(key.find("reduction in the contract's order (1)"), std::string::npos) << key;
    const auto [n, m] = vectorised(key);
    EXPECT_GE(m, 2) << key;
    EXPECT_LT(n, m) << key;
    const std::vector<std::string> loops = loop_lines(r.dump);
    ASSERT_EQ(static_cast<int>(loops.size()), m) << r.dump;
    int partials = 0, in_vectors = 0;
    for (const std::string& l : loops) {
      if (l.find("(the chunks' partial sums in order): not vectorised: reduction in the "
                 "contract's order") != std::string::npos)
        ++partials;
      if (l.find("(a sum's runs, four in vectors): not vectorised: already in vectors") !=
          std::string::npos)
        ++in_vectors;
    }
    EXPECT_EQ(partials, 1) << r.dump;
    EXPECT_EQ(in_vectors, 1) << r.dump;
  }
}

TEST(SimdReport, AMapThatFitsLanesReportsItsLanes) {
  if (!jit()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const SimdRun r = run("lanes", false);
  const std::string key = key_line(r.stats, "twice (line");
  ASSERT_NE(key, "") << r.stats;
  // (An SLP note may follow, as the host's vector width decides.)
  EXPECT_EQ(simd_note(key).rfind("SIMD: " + std::to_string(kLanes) + " elements at once", 0), 0u)
      << key;
  EXPECT_EQ(key.find("no lanes"), std::string::npos) << key;
}

TEST(SimdReport, AMapOutsideLanesSaysWhy) {
  if (!jit()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const SimdRun r = run("branches", false);
  const std::string key = key_line(r.stats, "flip (line");
  ASSERT_NE(key, "") << r.stats;
  EXPECT_NE(key.find("SIMD: no lanes (a local assigned in a branch); "), std::string::npos) << key;
  const auto [n, m] = vectorised(key);
  EXPECT_GE(m, 1) << key;
  EXPECT_GE(n, 0) << key;
}

// A fresh folder, removed with everything in it at the end of the test.
struct TempFolder {
  fs::path path;
  TempFolder() {
    std::random_device rd;
    path = fs::temp_directory_path() /
           ("simit_simd_report_test_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

TEST(SimdReport, AKernelFromTheCacheReportsWhatTheFreshOneDid) {
  if (!jit()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (const char* function : {"inner", "pass", "branches", "lanes"}) {
    SCOPED_TRACE(function);
    TempFolder dir;
    const SimdRun fresh = run(function, false, dir.path.string());
    const SimdRun cached = run(function, false, dir.path.string());
    EXPECT_EQ(fresh.stats.find("from the kernel cache"), std::string::npos) << fresh.stats;
    EXPECT_NE(cached.stats.find("from the kernel cache"), std::string::npos) << cached.stats;
    // Each trace's SIMD note, in order.
    auto notes = [](const std::string& stats) {
      std::vector<std::string> out;
      std::istringstream in(stats);
      for (std::string l; std::getline(in, l);)
        if (l.find("SIMD: ") != std::string::npos) out.push_back(simd_note(l));
      return out;
    };
    EXPECT_FALSE(notes(fresh.stats).empty()) << fresh.stats;
    EXPECT_EQ(notes(fresh.stats), notes(cached.stats));
  }
}

// ---------------------------------------------------------------------------
// The report as a cache entry keeps it

TEST(SimdReport, TheCacheEntrysTextReadsBackAsTheReport) {
  SimdReport r;
  r.reported = true;
  r.map = true;
  r.lanes = 1;
  r.lanes_why_not = "a local assigned in a branch";
  r.slp_groups = 3;
  r.loops.push_back({2, "vector pass", 4, 2, ""});
  r.loops.push_back({5, "a sum's runs one by one", 1, 1, "trip count unknown, indirect accesses"});
  SimdReport back;
  ASSERT_TRUE(read_simd_report(simd_report_text(r), back));
  EXPECT_TRUE(back.reported);
  EXPECT_TRUE(back.map);
  EXPECT_EQ(back.lanes, 1);
  EXPECT_EQ(back.lanes_why_not, "a local assigned in a branch");
  EXPECT_EQ(back.slp_groups, 3);
  ASSERT_EQ(back.loops.size(), 2u);
  EXPECT_EQ(back.loops[0].number, 2);
  EXPECT_EQ(back.loops[0].what, "vector pass");
  EXPECT_EQ(back.loops[0].width, 4);
  EXPECT_EQ(back.loops[0].interleave, 2);
  EXPECT_EQ(back.loops[1].why_not, "trip count unknown, indirect accesses");
  EXPECT_EQ(back.summary(), r.summary());
  EXPECT_EQ(r.summary(),
            "SIMD: no lanes (a local assigned in a branch); 1 of 2 loops vectorised (width 4); "
            "not: trip count unknown (1); SLP: 3 groups");
  // Tabs and line breaks in the words (the text's separators) read back as spaces.
  r.loops[0].what = "a\tb\nc";
  ASSERT_TRUE(read_simd_report(simd_report_text(r), back));
  ASSERT_EQ(back.loops.size(), 2u);
  EXPECT_EQ(back.loops[0].what, "a b c");
}

TEST(SimdReport, TextThatIsNotAReportIsRejected) {
  SimdReport r;
  for (const char* bad : {"", "simd\t1\t4\t1\t0\t", "loop\t1\t4\t1\tx\ty\n", "simd\t1\t0\t1\t0\t\n",
                          "simd\t2\t4\t1\t0\t\n", "simd\t1\t4\t1\t0\t\nloop\t1\tfour\t1\tx\t\n",
                          "simd\t1\t4\t1\t0\t\nloop\t1\t4\t1\tx\n"})
    EXPECT_FALSE(read_simd_report(bad, r)) << bad;
  EXPECT_TRUE(read_simd_report("simd\t0\t1\t0\t0\t\n", r));
  EXPECT_EQ(r.summary(), "SIMD: LLVM's vectorisers off (a large trace)");
}

}  // namespace
}  // namespace simit::jit
