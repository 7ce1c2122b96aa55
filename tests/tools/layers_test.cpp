// The layers of ARCHITECTURE.md as far as the front ends have reached them: no front end
// constructs an interpreter (they all run through api::Engine), and tools/, repl/ and
// src/scene/ include private headers of src/ only from the lists below. The lists are what is
// left to move behind the public API; a new private include has to be added here on purpose.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path kRoot = SIMIT_SOURCE_DIR;

std::vector<fs::path> sources(const std::string& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(kRoot / folder)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".cpp" || ext == ".h")) out.push_back(e.path());
  }
  return out;
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The headers of src/ layers (frontend/, interp/, runtime/, api/, ...) a file includes.
std::vector<std::string> private_includes(const fs::path& p) {
  static const std::regex include(R"(#include\s+"((frontend|interp|runtime|api|jit)/[^"]+)\")");
  std::vector<std::string> out;
  const std::string text = text_of(p);
  for (std::sregex_iterator it(text.begin(), text.end(), include), end; it != end; ++it)
    out.push_back((*it)[1]);
  return out;
}

void expect_only(const std::string& folder, const std::set<std::string>& allowed) {
  for (const fs::path& p : sources(folder))
    for (const std::string& h : private_includes(p))
      EXPECT_TRUE(allowed.count(h)) << fs::relative(p, kRoot).string() << " includes \"" << h
                                    << "\", which " << folder << "/ may not use";
}

TEST(Layers, OnlyTheEngineConstructsAnInterpreter) {
  static const std::regex construction(
      R"((make_unique|make_shared)\s*<\s*(simit::)?interp::Interpreter\s*>|(simit::)?interp::Interpreter\s+\w+\s*[({])");
  for (const char* folder : {"tools", "repl", "bench", "src/scene", "src/api"})
    for (const fs::path& p : sources(folder)) {
      if (p.filename() == "engine.cpp") continue;  // Engine::make_executor, the one place
      EXPECT_FALSE(std::regex_search(text_of(p), construction))
          << fs::relative(p, kRoot).string() << " constructs an interp::Interpreter; run through "
                                                "api::Engine instead";
    }
}

// The command line: the engine, and the frontend and values the test runner (TESTFORMAT.md)
// and `simit check --dump` work on.
TEST(Layers, ToolsIncludeOnlyTheirListedPrivateHeaders) {
  expect_only("tools", {"api/compiled_program.h", "api/engine.h", "frontend/ast.h",
                        "frontend/diagnostics.h", "frontend/frontend.h", "frontend/printer.h",
                        "frontend/types.h", "interp/operators.h", "interp/printing.h",
                        "interp/set_binding.h", "interp/value.h", "runtime/dense_linalg.h",
                        "runtime/set.h"});
}

// The REPL compiles its inputs itself and the step debugger inspects the running interpreter
// through its debugger interface (hook, inspection, values).
TEST(Layers, ReplIncludesOnlyTheEngineAndTheDebuggerInterface) {
  expect_only("repl", {"api/engine.h", "frontend/ast.h", "frontend/debug_expr.h",
                       "frontend/frontend.h", "frontend/intrinsics.h", "frontend/types.h",
                       "interp/hook.h", "interp/interpreter.h", "interp/printing.h",
                       "interp/runtime_error.h", "interp/set_binding.h", "interp/value.h",
                       "runtime/set.h", "runtime/tensor.h"});
}

// Scenes: the engine and its bindings, the runtime's sets and mesh readers and writers.
TEST(Layers, ScenesUseTheEngineAndTheMeshReadersOnly) {
  expect_only("src/scene", {"api/binding_check.h", "api/compiled_program.h", "api/engine.h",
                            "api/tensor_values.h", "interp/value.h", "runtime/fault.h",
                            "runtime/mesh/atomic_file.h", "runtime/mesh/mesh.h",
                            "runtime/mesh/mesh_reader.h", "runtime/mesh/pvd_writer.h",
                            "runtime/mesh/quicklook.h", "runtime/mesh/topology.h",
                            "runtime/set.h"});
}

}  // namespace
