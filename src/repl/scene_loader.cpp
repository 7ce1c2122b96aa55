// Scenes for the REPL through the scene library.
#include "scene_loader.h"

#include "scene/scene_sets.h"

namespace simit::repl {

std::optional<SceneData> load_scene(const std::string& path, bool float32, std::ostream& err) {
  std::optional<scene::SceneSets> built = scene::load_scene_sets(path, float32, err);
  if (!built) return std::nullopt;
  SceneData d;
  d.path = built->path;
  d.program_path = built->program_path;
  d.init = built->init;
  d.step = built->step;
  d.sets = built->sets;
  for (auto& [name, t] : built->tensors)
    d.tensors.emplace_back(
        name, t.shape().is_scalar() ? interp::Value::component(t, 0) : interp::Value::of_tensor(t));
  d.owner = built->owner;
  return d;
}

}  // namespace simit::repl
