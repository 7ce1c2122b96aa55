// simit.Program, simit.Function and simit.Matrix: programs compiled with an executor choice,
// functions whose bindings Python keeps alive, runs without the GIL, results as numpy arrays.
#include <pybind11/stl.h>

#include <map>
#include <optional>

#include "common.h"

namespace simit::python {

namespace {

// The executor the user named ("interpreter" or "jit", as `simit run --executor`), and the
// thread count (0: every core), parsed by the project's own parsers.
ExecutorChoice executor_choice(const std::string& backend, int threads) {
  ExecutorChoice choice;
  std::string error;
  std::optional<ExecutorKind> kind = parse_executor_kind(backend, error);
  if (!kind) throw Error(error);
  choice.kind = *kind;
  std::optional<int> n = parse_threads(std::to_string(threads), error);
  if (!n) throw Error("threads: " + error);
  choice.threads = *n;
  if (std::string why = executor_unavailable(choice); !why.empty()) throw Error(why);
  return choice;
}

// A DenseResult kept alive by the arrays made over it.
py::capsule owner_of(DenseResult r) {
  return py::capsule(new DenseResult(std::move(r)),
                     [](void* p) { delete static_cast<DenseResult*>(p); });
}

}  // namespace

py::object to_python(const DenseResult& r) {
  const std::vector<int> dims = r.dims();
  if (dims.empty()) {
    switch (r.kind()) {
      case ComponentKind::Int: return py::int_(r.ints()[0]);
      case ComponentKind::Float: return py::float_(r.floats()[0]);
      case ComponentKind::Bool: return py::bool_(r.bools()[0]);
      case ComponentKind::Complex: return py::cast(r.complexes()[0]);
    }
  }
  void* data = nullptr;
  switch (r.kind()) {
    case ComponentKind::Int: data = const_cast<int32_t*>(r.ints()); break;
    case ComponentKind::Float: data = const_cast<double*>(r.floats()); break;
    case ComponentKind::Bool: data = const_cast<bool*>(r.bools()); break;
    case ComponentKind::Complex: data = const_cast<double_complex*>(r.complexes()); break;
  }
  std::vector<py::ssize_t> shape(dims.begin(), dims.end());
  // Read-only: the result is shared with the function (a later result() gives the same).
  return view_array({r.kind(), {}, false}, shape, data, owner_of(r), false);
}

namespace {

// A block-CSR system matrix: arrays over the function's result, kept alive by a capsule.
struct PyMatrix {
  SystemMatrixView m;
  py::object indptr, indices, blocks;
};

PyMatrix make_matrix(SystemMatrixView m) {
  auto* keep = new SystemMatrixView(m);
  py::capsule owner(keep, [](void* p) { delete static_cast<SystemMatrixView*>(p); });
  PyMatrix out{m, py::none(), py::none(), py::none()};
  const FieldType index{ComponentKind::Int, {}, false};
  out.indptr = view_array(index, {static_cast<py::ssize_t>(m.row_ptr().size())},
                          const_cast<int32_t*>(m.row_ptr().data()), owner, false);
  out.indices = view_array(index, {static_cast<py::ssize_t>(m.col_idx().size())},
                           const_cast<int32_t*>(m.col_idx().data()), owner, false);
  const py::ssize_t nnz = static_cast<py::ssize_t>(m.col_idx().size());
  std::vector<py::ssize_t> shape{nnz, m.block_rows(), m.block_cols()};
  switch (m.kind()) {
    case ComponentKind::Float:
      out.blocks = view_array({ComponentKind::Float, {}, false}, shape,
                              const_cast<double*>(m.values().data()), owner, false);
      break;
    case ComponentKind::Complex:
      out.blocks = view_array({ComponentKind::Complex, {}, false}, shape,
                              const_cast<double_complex*>(m.complexes().data()), owner, false);
      break;
    default:
      out.blocks = view_array({ComponentKind::Int, {}, false}, shape,
                              const_cast<int32_t*>(m.ints().data()), owner, false);
      break;
  }
  return out;
}

// A Function with what Python bound to it: the objects it must keep alive, and the copies it
// owns for values that could not be bound by reference.
struct PyFunction {
  Function f;
  std::map<std::string, py::object> kept;
  std::map<std::string, py::array> copies;

  void bind(const std::string& name, py::object value) {
    if (py::isinstance<PySet>(value)) {
      PySet& s = value.cast<PySet&>();
      if (!s.owned())
        throw Error("the sets of a simit.Scene run in the scene; bind sets made with simit.Set");
      f.bind(name, *s.owned());
      kept[name] = value;
      copies.erase(name);
      return;
    }
    const std::optional<FieldType> type = f.tensor_type(name);
    if (!type)
      throw BindError({"'" + name + "' is a set or a tensor whose size depends on a set: bind " +
                       "a simit.Set to a set extern"});
    const py::dtype dt = dtype_of(type->kind, type->single);
    py::array array;
    bool by_reference = false;
    if (py::isinstance<py::array>(value)) {
      py::array a = value.cast<py::array>();
      by_reference = a.dtype().equal(dt) && (a.flags() & py::array::c_style) && a.writeable();
      if (by_reference) array = a;
    }
    if (!by_reference) {
      try {
        array = py::module_::import("numpy").attr("array")(value, dt, py::arg("order") = "C");
      } catch (const py::error_already_set& e) {
        throw BindError({"'" + name + "': cannot convert the value to " +
                         py::str(py::handle(dt)).cast<std::string>() + ": " + e.what()});
      }
    }
    TensorSlot slot;
    slot.kind = type->kind;
    slot.single = type->single;
    for (py::ssize_t i = 0; i < array.ndim(); ++i) slot.dims.push_back(array.shape(i));
    slot.data = array.mutable_data();
    f.bind(name, slot);
    kept[name] = array;
    if (by_reference)
      copies.erase(name);
    else
      copies[name] = array;
  }
};

}  // namespace

void register_program(py::module_& m) {
  py::class_<PyMatrix>(m, "Matrix", "A system matrix in block CSR (indptr, indices, blocks).")
      .def_readonly("indptr", &PyMatrix::indptr)
      .def_readonly("indices", &PyMatrix::indices)
      .def_readonly("blocks", &PyMatrix::blocks)
      .def_property_readonly(
          "block_shape",
          [](const PyMatrix& p) { return py::make_tuple(p.m.block_rows(), p.m.block_cols()); })
      .def_property_readonly("shape",
                             [](const PyMatrix& p) {
                               return py::make_tuple(p.m.rows() * p.m.block_rows(),
                                                     p.m.cols() * p.m.block_cols());
                             })
      .def(
          "__iter__",
          [](const PyMatrix& p) { return py::iter(py::make_tuple(p.indptr, p.indices, p.blocks)); })
      .def("to_scipy", [](const PyMatrix& p) {
        py::module_ sparse = py::module_::import("scipy.sparse");
        return sparse.attr("bsr_matrix")(
            py::make_tuple(p.blocks, p.indices, p.indptr),
            py::arg("shape") =
                py::make_tuple(p.m.rows() * p.m.block_rows(), p.m.cols() * p.m.block_cols()));
      });

  py::class_<PyFunction>(m, "Function", "A compiled function: bind, init, run, read results.")
      .def_property_readonly("name", [](const PyFunction& p) { return p.f.name(); })
      .def("bind", &PyFunction::bind, py::arg("name"), py::arg("value"))
      .def("unbound", [](const PyFunction& p) { return p.f.unbound(); })
      .def("init", [](PyFunction& p) { p.f.init(); })
      .def("run",
           [](PyFunction& p) {
             // Bound arrays stay alive (kept) and nothing else in Python is touched.
             FlushStdoutAtExit flush;
             py::gil_scoped_release release;
             p.f.run();
           })
      .def("result",
           [](PyFunction& p, const std::string& name) -> py::object {
             return to_python(p.f.result(name));
           })
      .def("matrix",
           [](PyFunction& p, const std::string& name) { return make_matrix(p.f.matrix(name)); })
      .def_property_readonly("executor", [](const PyFunction& p) {
        return std::string(executor_name(p.f.executor().kind));
      });

  py::class_<Program>(m, "Program", "A Simit program, from a file or a string.")
      .def(py::init([](std::optional<std::string> path, std::optional<std::string> source,
                       const std::string& backend, int threads, bool float32, bool check_finite) {
             if (path.has_value() == source.has_value())
               throw Error("Program(path) or Program(source=...): give exactly one");
             Options o;
             o.executor = executor_choice(backend, threads);
             o.float_size = float32 ? 4 : 8;
             o.check_finite = check_finite;
             o.stop_on_interrupt = true;
             o.out = &python_stdout();
             auto p = std::make_unique<Program>(o);
             if (path)
               p->load_file(*path);
             else
               p->load_string(*source, "<source>");
             return p;
           }),
           py::arg("path") = py::none(), py::kw_only(), py::arg("source") = py::none(),
           py::arg("backend") = "interpreter", py::arg("threads") = 0, py::arg("float32") = false,
           py::arg("check_finite") = false)
      .def("functions", &Program::function_names)
      .def("compile", [](const Program& p, const std::string& name) {
        return PyFunction{p.compile(name), {}, {}};
      });
}

}  // namespace simit::python
