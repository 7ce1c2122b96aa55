// SIMIT_PERF_MAP (docs/jit.md, "Profiling compiled kernels"): a run under the JIT lists each
// function it links in /tmp/perf-PID.map, named by its trace, so that `perf report` names
// the time spent in compiled code; without the variable nothing is listed.
#include "cli.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

struct Entry {
  unsigned long long start = 0, size = 0;
  std::string name;
};

class PerfMap : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
    std::string pattern = (fs::temp_directory_path() / "simit-perf-map-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    map_ = "/tmp/perf-" + std::to_string(getpid()) + ".map";  // where perf looks
    fs::remove(map_);
  }
  void TearDown() override {
    unsetenv("SIMIT_PERF_MAP");
    std::error_code ec;
    fs::remove(map_, ec);
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  // One frame of the fem example under the JIT, compiled afresh (no kernel cache).
  int run_fem() {
    const std::string scene = std::string(SIMIT_SOURCE_DIR) + "/examples/fem/bunny.toml";
    std::vector<std::string> args = {
        "simit", "run",         "--executor", "jit",      "--frames",    "1",  "--threads",
        "1",     "--jit-cache", "off",        "--output", dir_.string(), scene};
    std::vector<const char*> argv;
    for (const auto& a : args) argv.push_back(a.c_str());
    std::ostringstream out, err;
    const int status = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
    EXPECT_EQ(status, 0) << err.str();
    return status;
  }

  // The map's lines, each checked against perf's "START SIZE name" format.
  std::vector<Entry> read_map() const {
    std::vector<Entry> entries;
    std::ifstream in(map_);
    const std::regex line("([0-9a-f]+) ([0-9a-f]+) (.+)");
    std::string text;
    while (std::getline(in, text)) {
      std::smatch m;
      EXPECT_TRUE(std::regex_match(text, m, line)) << text;
      if (!std::regex_match(text, m, line)) continue;
      entries.push_back({std::stoull(m[1], nullptr, 16), std::stoull(m[2], nullptr, 16), m[3]});
    }
    return entries;
  }

  fs::path dir_;
  std::string map_;
};

TEST_F(PerfMap, ListsEveryCompiledFunctionByItsTrace) {
  setenv("SIMIT_PERF_MAP", "1", 1);
  ASSERT_EQ(run_fem(), 0);
  std::vector<Entry> entries = read_map();
  ASSERT_FALSE(entries.empty()) << "nothing listed in " << map_;
  const std::regex map_kernel(R"(tet_force:\d+ \[simit_kernel_\d+\])");
  const std::regex pass(R"(statements:\d+-\d+ \[simit_kernel_\d+\.op\d+\])");
  int maps = 0, passes = 0;
  for (const Entry& e : entries) {
    EXPECT_GT(e.size, 0u) << e.name;
    EXPECT_NE(e.start, 0u) << e.name;
    maps += std::regex_match(e.name, map_kernel) ? 1 : 0;
    passes += std::regex_match(e.name, pass) ? 1 : 0;
  }
  EXPECT_EQ(maps, 1) << "the map on tet_force, once";
  EXPECT_GE(passes, 3) << "the CG solver loop's passes, each a function of its own";
  // No two functions overlap: each address perf samples names one function.
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.start < b.start; });
  for (size_t i = 1; i < entries.size(); ++i)
    EXPECT_LE(entries[i - 1].start + entries[i - 1].size, entries[i].start)
        << entries[i - 1].name << " overlaps " << entries[i].name;
}

TEST_F(PerfMap, ListsNothingWithoutTheVariable) {
  for (const char* off : {"", "0"}) {
    setenv("SIMIT_PERF_MAP", off, 1);
    ASSERT_EQ(run_fem(), 0);
    EXPECT_FALSE(fs::exists(map_)) << "SIMIT_PERF_MAP=\"" << off << "\"";
  }
  unsetenv("SIMIT_PERF_MAP");
  ASSERT_EQ(run_fem(), 0);
  EXPECT_FALSE(fs::exists(map_));
}

}  // namespace
}  // namespace simit::tools
