// The layers of ARCHITECTURE.md: no front end constructs an interpreter (they all run through
// api::Engine), tools/ and repl/ include no private header of src/, the public headers none
// either, and src/scene/ only those listed below (a new one has to be added here on purpose).
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

// The headers of src/ (frontend/, interp/, runtime/, api/, scene/, ...) a file includes.
std::vector<std::string> private_includes(const fs::path& p) {
  static const std::regex include(
      R"(#include\s+"((frontend|interp|runtime|api|jit|scene|testing|commands|repl)/[^"]+)\")");
  std::vector<std::string> out;
  const std::string text = text_of(p);
  for (std::sregex_iterator it(text.begin(), text.end(), include), end; it != end; ++it)
    out.push_back((*it)[1]);
  return out;
}

// A layer under src/ may include its own headers; a front end has none under src/.
void expect_only(const std::string& folder, const std::set<std::string>& allowed) {
  const std::string own =
      folder.starts_with("src/") ? fs::path(folder).filename().string() + "/" : std::string();
  for (const fs::path& p : sources(folder))
    for (const std::string& h : private_includes(p))
      EXPECT_TRUE(allowed.count(h) || (!own.empty() && h.starts_with(own)))
          << fs::relative(p, kRoot).string() << " includes \"" << h << "\", which " << folder
          << "/ may not use";
}

TEST(Layers, OnlyTheEngineConstructsAnInterpreter) {
  static const std::regex construction(
      R"((make_unique|make_shared)\s*<\s*(simit::)?interp::Interpreter\s*>|(simit::)?interp::Interpreter\s+\w+\s*[({])");
  for (const char* folder : {"tools", "repl", "bench", "src/scene", "src/api", "src/repl",
                             "src/testing", "src/commands"})
    for (const fs::path& p : sources(folder)) {
      if (p.filename() == "engine.cpp") continue;  // Engine::make_executor, the one place
      EXPECT_FALSE(std::regex_search(text_of(p), construction))
          << fs::relative(p, kRoot).string()
          << " constructs an interp::Interpreter; run through "
             "api::Engine instead";
    }
}

// The front ends include no private header of src/ at all. The build refuses one too (their
// libraries see include/ only; tests/CMakeLists.txt's layers_*_refuse_private_headers
// compile a probe to show it); this names the file and the header at once.
TEST(Layers, ToolsIncludeNoPrivateHeader) { expect_only("tools", {}); }
TEST(Layers, ReplIncludesNoPrivateHeader) { expect_only("repl", {}); }

// The public headers name no header of src/: runtime, frontend and interpreter types appear in
// them at most as opaque forward declarations, so a host cannot reach inside.
TEST(Layers, PublicHeadersIncludeOnlyPublicHeaders) {
  static const std::regex include(R"(#include\s+"([^"]+)\")");
  for (const fs::path& p : sources("include")) {
    const std::string text = text_of(p);
    for (std::sregex_iterator it(text.begin(), text.end(), include), end; it != end; ++it)
      EXPECT_TRUE(std::string((*it)[1]).starts_with("simit/"))
          << fs::relative(p, kRoot).string() << " includes \"" << (*it)[1] << "\"";
  }
}

// Scenes: the engine and its bindings, the runtime's sets, mesh readers, writers and
// renumbering, and the project's math functions (scene expressions compute as programs do);
// and the interpreter's seam of a distributed run, which the scene's (scene/distributed.h)
// extends for src/dist to implement.
TEST(Layers, ScenesUseTheEngineAndTheMeshReadersOnly) {
  expect_only("src/scene", {"api/binding_check.h",
                            "api/compiled_program.h",
                            "api/engine.h",
                            "api/set_access.h",
                            "api/stop_on_sigint.h",
                            "api/tensor_values.h",
                            "interp/distribution.h",
                            "interp/value.h",
                            "runtime/fault.h",
                            "runtime/math/math_functions.h",
                            "runtime/mesh/atomic_file.h",
                            "runtime/mesh/mesh.h",
                            "runtime/mesh/mesh_reader.h",
                            "runtime/mesh/pvd_writer.h",
                            "runtime/mesh/vtu_writer.h",
                            "runtime/mesh/quicklook.h",
                            "runtime/mesh/reorder.h",
                            "runtime/mesh/topology.h",
                            "runtime/set.h",
                            "runtime/tensor.h"});
}

}  // namespace
