// simit.Scene: a scene file opened as `simit run` opens it, its sets as numpy views, stepped a
// frame at a time without the GIL (scene.run, with its progress, is in simit/__init__.py).
#include <pybind11/stl.h>

#include <sstream>

#include "common.h"

namespace simit::python {

namespace {

struct PyScene {
  std::unique_ptr<scene::Scene> scene;
  std::unique_ptr<scene::Stepper> stepper;
};

// `output`: None, the scene's [output]; False, nothing; a folder, the scene's output there.
void apply_output(scene::SceneOptions& o, const py::object& output) {
  if (output.is_none()) return;
  if (py::isinstance<py::bool_>(output)) {
    if (output.cast<bool>())
      throw Error("output: None (the scene's [output]), False (no files) or a folder");
    o.quiet = true;
    return;
  }
  o.output_dir = py::str(py::module_::import("os").attr("fspath")(output));
  if (o.output_dir.empty()) throw Error("output: the folder name is empty");
}

}  // namespace

void register_scene(py::module_& m) {
  py::class_<PyScene>(m, "Scene", "A scene file: its program, meshes, sets and output.")
      .def(py::init([](py::object path, std::optional<std::string> backend,
                       std::optional<int> threads, py::object output, bool float32,
                       bool check_finite, bool reorder) {
             scene::SceneOptions o;
             o.file = py::str(py::module_::import("os").attr("fspath")(path));
             std::string error;
             if (backend) {
               std::optional<ExecutorKind> kind = parse_executor_kind(*backend, error);
               if (!kind) throw Error(error);
               o.executor.kind = *kind;
               o.executor_given = true;
             }
             if (threads) {
               std::optional<int> n = parse_threads(std::to_string(*threads), error);
               if (!n) throw Error("threads: " + error);
               o.executor.threads = *n;
               o.threads_given = true;
             }
             apply_output(o, output);
             o.float32 = float32;
             o.check_finite = check_finite;
             o.keep_mesh_order = !reorder;
             o.stop_on_interrupt = true;
             std::ostringstream err;
             auto s = std::make_unique<PyScene>();
             s->scene = scene::Scene::open(o, err);
             if (!s->scene) {
               std::string text = err.str();
               while (!text.empty() && text.back() == '\n') text.pop_back();
               throw Error(text);
             }
             s->stepper = std::make_unique<scene::Stepper>(*s->scene, python_stdout());
             return s;
           }),
           py::arg("path"), py::kw_only(), py::arg("backend") = py::none(),
           py::arg("threads") = py::none(), py::arg("output") = py::none(),
           py::arg("float32") = false, py::arg("check_finite") = false, py::arg("reorder") = false)
      .def_property_readonly("sets",
                             [](py::object self) {
                               // Made afresh (not cached: a set holds its scene, and a cache
                               // in the scene would make a cycle Python cannot collect).
                               py::dict sets;
                               for (const scene::SetView& v : self.cast<PyScene&>().stepper->sets())
                                 sets[py::str(v.name)] = py::cast(PySet(v, self));
                               return sets;
                             })
      .def_property_readonly("frame", [](const PyScene& s) { return s.stepper->frame(); })
      .def_property_readonly("frames", [](const PyScene& s) { return s.scene->frames(); })
      .def_property_readonly("initialised",
                             [](const PyScene& s) { return s.stepper->initialised(); })
      .def_property_readonly("program_path",
                             [](const PyScene& s) { return s.scene->program_path(); })
      .def("init",
           [](PyScene& s) {
             FlushStdoutAtExit flush;
             py::gil_scoped_release release;
             s.stepper->init();
           })
      .def("step",
           [](PyScene& s) {
             std::vector<std::pair<std::string, DenseResult>> results;
             {
               FlushStdoutAtExit flush;
               py::gil_scoped_release release;
               results = s.stepper->step();
             }
             py::dict out;
             for (const auto& [name, r] : results) out[py::str(name)] = to_python(r);
             return out;
           })
      .def("close",
           [](PyScene& s) {
             py::gil_scoped_release release;
             s.stepper->finish();
           })
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](PyScene& s, py::args) {
        py::gil_scoped_release release;
        s.stepper->finish();
      });
}

}  // namespace simit::python
