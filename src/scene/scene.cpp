// The public scene API: a scene opened once, run or built as often as asked, its problems
// reported the way `simit run` prints them.
#include "simit/scene.h"

#include <memory>
#include <new>

#include "runtime/mesh/atomic_file.h"
#include "runtime/mesh/mesh.h"
#include "scene/scene_impl.h"
#include "scene/scene_run.h"
#include "scene/scene_sets.h"

namespace simit::scene {

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::~Scene() = default;

std::unique_ptr<Scene> Scene::open(const SceneOptions& options, std::ostream& err) {
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  // A choice the command line made is checked before the file is read.
  if (std::string bad = executor_unavailable(options.executor); !bad.empty()) {
    err << options.file << ": error: " << bad << "\n";
    return nullptr;
  }
  try {
    impl->file = read_scene_file(options.file);
    // The scene's own keys choose what the command line left open.
    const SceneFile& file = *impl->file;
    ExecutorChoice& choice = impl->options.executor;
    if (file.executor && !options.executor_given) choice.kind = *file.executor;
    if (file.threads && !options.threads_given) choice.threads = *file.threads;
    if (file.jit_cache && !options.jit_cache_given) choice.jit_cache = *file.jit_cache;
    if (std::string bad = executor_unavailable(choice); !bad.empty())
      file.fail(file.doc.get("executor"), "executor: " + bad);
    // What says something about the JIT only would do nothing, silently, under the interpreter.
    if (!compiles(choice.kind) && (choice.check || options.jit_stats))
      throw SceneError(options.file + ": error: " + (choice.check ? "--check-jit" : "--jit-stats") +
                       " needs the JIT: --executor jit, or executor = \"jit\" in the scene");
  } catch (const SceneError& e) {
    err << e.what() << "\n";
    return nullptr;
  } catch (const std::exception& e) {
    err << options.file << ": error: " << e.what() << "\n";
    return nullptr;
  }
  return std::unique_ptr<Scene>(new Scene(std::move(impl)));
}

const std::string& Scene::program_path() const { return impl_->file->program_path; }

int Scene::frames() const {
  return impl_->options.frames >= 0 ? impl_->options.frames : impl_->file->frames;
}

std::unique_ptr<Scene> SceneAccess::open(const SceneOptions& options, interp::Trap* trap,
                                         std::ostream& err) {
  std::unique_ptr<Scene> scene = Scene::open(options, err);
  if (scene) scene->impl_->trap = trap;
  return scene;
}

const ExecutorChoice& SceneAccess::executor(const Scene& scene) {
  return scene.impl_->options.executor;
}

const frontend::ast::Program& SceneAccess::program(const Scene& scene) {
  return scene.impl_->file->program->program();
}

int Scene::run(std::ostream& out, std::ostream& err, int frames) {
  const SceneOptions& o = impl_->options;
  const int count = frames >= 0 ? frames : this->frames();
  std::unique_ptr<SceneRun> run;  // outlives the try: --jit-stats prints after the error
  try {
    run = std::make_unique<SceneRun>(*impl_->file, o, impl_->meshes, impl_->reorder(), impl_->trap);
    run->build();
    run->run(count, out);
  } catch (const SceneError& e) {
    out.flush();
    err << e.what() << "\n";
    return 1;
  } catch (const RunFailure& e) {  // a run-time error, a NaN stop, an interrupt
    out.flush();
    err << e.what() << "\n";
    if (run) run->print_jit_stats(out);
    return 1;
  } catch (const runtime::MeshError& e) {
    out.flush();
    err << o.file << ": error: writing output: " << e.what() << "\n";
    if (run) run->print_jit_stats(out);
    return 1;
  } catch (const std::bad_alloc&) {  // what was being allocated is not known here
    out.flush();
    err << o.file << ": error: out of memory while building or running the scene\n";
    if (run) run->print_jit_stats(out);
    return 1;
  } catch (const std::exception& e) {
    out.flush();
    err << "simit run: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

std::optional<SceneSets> SceneAccess::build(Scene& scene, std::ostream& err) {
  const std::unique_ptr<Scene::Impl>& impl_ = scene.impl_;
  // The REPL indexes these sets by element (`:print verts.x[3]`): each mesh's own order.
  auto run = std::make_shared<SceneRun>(*impl_->file, impl_->options, impl_->meshes, Reorder::Off,
                                        impl_->trap);
  try {
    run->build();
  } catch (const SceneError& e) {
    err << e.what() << "\n";
    return std::nullopt;
  } catch (const std::exception& e) {
    err << impl_->options.file << ": error: " << e.what() << "\n";
    return std::nullopt;
  }
  SceneSets d;
  d.path = impl_->options.file;
  d.program_path = impl_->file->program_path;
  d.init = impl_->file->init_name;
  d.step = impl_->file->step_name;
  for (const auto& s : run->sets().sets) d.sets.emplace_back(s->name, s->set.get());
  for (const frontend::ast::Variable* g : impl_->file->program->program().globals) {
    auto t = run->tensors().find(g->name);
    if (g->kind == frontend::ast::Variable::Kind::Extern && t != run->tensors().end())
      d.tensors.emplace_back(g->name, t->second.value.to_tensor());
  }
  d.owner = run;
  return d;
}

void remove_temporaries_on_signals() { runtime::remove_temporaries_on_signals(); }

int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err) {
  std::unique_ptr<Scene> scene = Scene::open(options, err);
  return scene ? scene->run(out, err) : 1;
}

std::optional<SceneSets> load_scene_sets(const std::string& path, bool float32, std::ostream& err) {
  SceneOptions options;
  options.file = path;
  options.float32 = float32;
  std::shared_ptr<Scene> scene = Scene::open(options, err);
  if (!scene) return std::nullopt;
  std::optional<SceneSets> sets = SceneAccess::build(*scene, err);
  if (sets)
    sets->owner = std::make_shared<std::pair<std::shared_ptr<Scene>, std::shared_ptr<void>>>(
        scene, sets->owner);
  return sets;
}

}  // namespace simit::scene
