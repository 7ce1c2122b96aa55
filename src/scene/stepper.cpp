// scene::Stepper: a scene run a frame at a time by its host, over the same SceneRun that
// `simit run` uses, with the sets' storage pinned so that the host's views stay valid.
#include <memory>
#include <new>

#include "api/set_access.h"
#include "runtime/mesh/mesh.h"
#include "scene/scene_impl.h"
#include "scene/scene_run.h"

namespace simit::scene {

struct Stepper::Impl {
  std::string file;  // the scene file, for messages
  std::shared_ptr<SceneRun> run;
  std::vector<SetView> sets;
  bool initialised = false;
  int frame = 0;
  int finished_at = -1;  // the frame finish() last wrote, -1 before
};

namespace {

// The errors of a SceneRun as the public API's: a message that is complete as it is.
template <class F>
auto translated(const std::string& scene_file, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const RunFailure& e) {
    if (e.interrupted) throw Interrupted(e.what(), e.line);
    throw RuntimeError(e.what(), e.line);
  } catch (const SceneError& e) {
    throw Error(e.what());
  } catch (const runtime::MeshError& e) {
    throw Error(scene_file + ": error: writing output: " + e.what());
  } catch (const std::bad_alloc&) {
    throw Error(scene_file + ": error: out of memory while building or running the scene");
  }
}

SetView view_of(const SceneSet& s) {
  runtime::Set& set = *s.set;
  set.pin_fields();  // the host's views of the fields must never be left behind
  SetView v;
  v.name = s.name;
  v.size = set.size();
  v.arity = set.arity();
  for (const runtime::Set* e : set.endpoint_sets()) v.endpoint_sets.push_back(e->name());
  if (v.arity > 0) v.endpoints = set.endpoints();
  for (int k = 0; k < set.field_count(); ++k) {
    runtime::Field& f = set.field(k);
    const runtime::FieldType& t = f.type();
    v.fields.push_back(
        FieldView{f.name(), FieldType{api::host_kind(t.kind), t.dims, t.single}, f.bytes()});
  }
  if (set.has_mesh_numbers()) v.mesh_numbers = set.mesh_numbers().data();
  return v;
}

}  // namespace

Stepper::Stepper(Scene& scene, std::ostream& out) : impl_(std::make_unique<Impl>()) {
  Scene::Impl& si = *scene.impl_;
  impl_->file = si.options.file;
  translated(impl_->file, [&] {
    impl_->run = std::make_shared<SceneRun>(*si.file, si.options, si.meshes, si.reorder(), si.trap);
    impl_->run->build();
    for (const auto& s : impl_->run->sets().sets) impl_->sets.push_back(view_of(*s));
    impl_->run->prepare(out);
    return 0;
  });
}

Stepper::~Stepper() = default;

const std::vector<SetView>& Stepper::sets() const { return impl_->sets; }
bool Stepper::initialised() const { return impl_->initialised; }
int Stepper::frame() const { return impl_->frame; }

void Stepper::init() {
  if (impl_->initialised) throw Error("the scene is already initialised (init runs once)");
  translated(impl_->file, [&] {
    impl_->run->initialise(false);
    return 0;
  });
  impl_->initialised = true;
}

std::vector<std::pair<std::string, DenseResult>> Stepper::step() {
  if (!impl_->initialised) init();
  FrameResult r =
      translated(impl_->file, [&] { return impl_->run->frame(impl_->frame + 1, false); });
  ++impl_->frame;
  std::vector<std::pair<std::string, DenseResult>> out;
  const std::vector<frontend::ast::Param>& declared = impl_->run->step_function().results;
  for (size_t i = 0; i < r.results.size() && i < declared.size(); ++i) {
    const interp::Value& v = r.results[i];
    if (!v.is_scalar() && !v.is_tensor()) continue;  // system matrices are not step results
    out.emplace_back(declared[i].name,
                     DenseResult(std::make_shared<const runtime::Tensor>(v.to_tensor())));
  }
  return out;
}

void Stepper::finish() {
  if (!impl_->initialised || impl_->finished_at == impl_->frame) return;
  translated(impl_->file, [&] {
    impl_->run->finish(impl_->frame);
    return 0;
  });
  impl_->finished_at = impl_->frame;
}

}  // namespace simit::scene
