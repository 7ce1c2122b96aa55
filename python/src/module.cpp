// The module simit._simit: its parts registered, and the API's errors turned into the
// package's exception classes (simit/_errors.py) with their fields.
#include <pybind11/stl.h>

#include "common.h"

namespace simit::python {

namespace {

// The package's exception classes, looked up once (they live as long as the interpreter).
struct ErrorClasses {
  py::handle error, compile_error, bind_error, runtime_error, diagnostic;
};

ErrorClasses& classes() {
  static ErrorClasses c;
  return c;
}

void raise(py::handle cls, py::object instance) { PyErr_SetObject(cls.ptr(), instance.ptr()); }

}  // namespace

void register_errors(py::module_& m) {
  py::module_ errors = py::module_::import("simit._errors");
  ErrorClasses& c = classes();
  c.error = py::object(errors.attr("Error")).release();
  c.compile_error = py::object(errors.attr("CompileError")).release();
  c.bind_error = py::object(errors.attr("BindError")).release();
  c.runtime_error = py::object(errors.attr("RuntimeError")).release();
  c.diagnostic = py::object(errors.attr("Diagnostic")).release();
  (void)m;
  py::register_exception_translator([](std::exception_ptr p) {
    const ErrorClasses& c = classes();
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const CompileError& e) {
      py::list diagnostics;
      for (const Diagnostic& d : e.diagnostics())
        diagnostics.append(py::reinterpret_borrow<py::object>(c.diagnostic)(
            d.line, d.column, d.category, d.message, d.rendered));
      raise(c.compile_error, py::reinterpret_borrow<py::object>(c.compile_error)(
                                 std::string(e.what()), diagnostics));
    } catch (const BindError& e) {
      raise(c.bind_error, py::reinterpret_borrow<py::object>(c.bind_error)(std::string(e.what()),
                                                                           py::cast(e.problems())));
    } catch (const RuntimeError& e) {
      raise(c.runtime_error,
            py::reinterpret_borrow<py::object>(c.runtime_error)(std::string(e.what()), e.line()));
    } catch (const Error& e) {
      raise(c.error, py::reinterpret_borrow<py::object>(c.error)(std::string(e.what())));
    }
  });
}

}  // namespace simit::python

PYBIND11_MODULE(_simit, m) {
  using namespace simit::python;
  m.doc() = "Simit: physical simulation programs, run from Python with numpy views of fields";
  m.attr("__version__") = SIMIT_VERSION;
  m.def("jit_available", &simit::jit_available,
        "Whether this build has the JIT (built with LLVM): backend=\"jit\" needs it.");
  m.def("default_threads", &simit::default_threads,
        "Every core this process may use: what threads=0 means.");
  register_errors(m);
  register_sets(m);
  register_program(m);
  register_scene(m);
  register_mesh(m);
}
