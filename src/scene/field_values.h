// [sets.S.fields]: initial field values of a set's elements: a constant per component, the
// mesh position, or an expression of the element's position (scene/scene_expr.h).
#pragma once

#include "runtime/mesh/mesh.h"
#include "scene/mesh_binding.h"
#include "scene/scene_file.h"

namespace simit::scene {

// Fills the fields [sets.NAME.fields] lists; `m` is the set's mesh. Throws SceneError.
void init_fields(const SceneFile& file, SceneSet& s, const runtime::Mesh& m);

}  // namespace simit::scene
