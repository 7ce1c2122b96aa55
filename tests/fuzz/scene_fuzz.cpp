// libFuzzer target of scene files: the input is a scene (TOML) beside a fixed program and
// meshes; it is read, its program compiled, its tensors read and its sets built with their
// field expressions, and nothing runs or is written. The input is also tried as a field
// expression on its own.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fuzz_support.h"
#include "scene/scene_expr.h"
#include "scene/scene_run.h"

namespace {

using namespace simit;

const char* const kProgram = R"(element Vertex
  x : vector[3](float);
  h : float;
  pinned : bool;
end
element Tet
  w : float;
end
element Face
  a : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);
extern skin : set{Vertex};
extern faces : set{Face}(skin, skin, skin);
extern dt : float;
extern g : vector[3](float);
extern count : int;

func lift(inout v : Vertex)
  if not v.pinned
    v.x(1) = v.x(1) + dt;
  end
end

export func init()
  apply lift to verts;
end

export func step() -> (n : int)
  count = count + 1;
  n = count;
end
)";

// One tet, and a square of two triangles.
const char* const kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const char* const kEle = "1 4 0\n0 0 1 2 3\n";
const char* const kObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

void write_partners() {
  static bool written = false;
  if (written) return;
  fuzz::write_scratch("tet.sim", kProgram);
  fuzz::write_scratch("tet.node", kNode);
  fuzz::write_scratch("tet.ele", kEle);
  fuzz::write_scratch("square.obj", kObj);
  written = true;
}

// A generated cloth of n points per side may be as large as 4096^2 points by design; inputs
// that ask for more than a small one would measure the allocator, not the scene reader.
bool generates_large_mesh(const toml::table& doc) {
  const toml::table* sets = doc["sets"].as_table();
  if (!sets) return false;
  for (auto&& [name, node] : *sets) {
    const toml::table* t = node.as_table();
    if (!t) continue;
    if (auto n = (*t)["n"].value<int64_t>(); n && *n > 64) return true;
  }
  return false;
}

void read_scene(std::string_view text) {
  std::string path = fuzz::write_scratch("scene.toml", text);
  try {
    // The reader screens what toml++ 3.3 would crash on (characters outside ASCII outside
    // strings and comments) before it parses.
    std::unique_ptr<scene::SceneFile> file = scene::read_scene_file(path);
    if (generates_large_mesh(file->doc)) return;
    scene::SceneOptions options;
    options.file = path;
    options.quiet = true;
    scene::MeshCache meshes;
    scene::SceneRun run(*file, options, meshes, file->reorder);
    run.build();
  } catch (const scene::SceneError& e) {
    if (std::string(e.what()).find(path) == std::string::npos)
      fuzz::invariant_broken("scene_fuzz",
                             std::string("the error does not name the scene: ") + e.what());
    fuzz::note_rejected("scene_fuzz", e.what());
  }
}

void evaluate_expression(std::string_view text) {
  const double p[3] = {0.25, 0.5, 0.75}, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  try {
    scene::PositionExpr e{std::string(text)};
    (void)e.eval(p, lo, hi);
  } catch (const std::invalid_argument& e) {
    fuzz::note_rejected("scene_fuzz", std::string("expression: ") + e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  write_partners();
  std::string_view text = fuzz::as_text(data, size);
  read_scene(text);
  evaluate_expression(text);
  return 0;
}
