// [tensors]: the values of the program's extern tensors (scalars, or dense tensors of fixed
// size given as a flat or nested array of their components, row-major), checked against the
// declared types and converted once into the values the engine binds.
#pragma once

#include <map>
#include <string>

#include "interp/value.h"
#include "scene/scene_file.h"

namespace simit::scene {

struct SceneTensor {
  const frontend::ast::Variable* var = nullptr;  // the program's extern
  interp::Value value;                           // binary32-rounded under float32
};

// By name. Throws SceneError naming the key, the value or the component that does not fit.
std::map<std::string, SceneTensor> read_tensors(const SceneFile& file, bool float32);

}  // namespace simit::scene
