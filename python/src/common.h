// What the binding files share: numpy dtypes of Simit's component kinds, the Python Set
// (made in Python or a view of a scene's), and the registration of each part of the module.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "simit/program.h"
#include "simit/scene.h"
#include "simit/set.h"

namespace simit::python {

namespace py = pybind11;

// The numpy dtype of a component kind (binary32 floats when `single`).
py::dtype dtype_of(ComponentKind kind, bool single);
// The component kind a dtype (or Python type: float, int, bool, complex) stands for; throws
// simit::Error for any other.
FieldType field_type_of(const py::handle& dtype, const std::vector<int>& dims);

// An array over `data` of shape `dims` and `type`'s dtype that keeps `base` alive (no copy).
py::array view_array(const FieldType& type, std::vector<py::ssize_t> dims, void* data,
                     py::handle base, bool writeable = true);

// A set as Python sees it: one made in Python (fixed size, fields pinned so that views never
// move), or a view of a scene's set (which the scene owns; `keep` holds the scene).
class PySet {
 public:
  struct Field {
    std::string name;
    FieldType type;
    void* data = nullptr;
  };

  // A vertex set of `size` elements.
  PySet(int size, const std::string& name);
  // An edge set: one element per row of `connectivity`, an element of endpoint set k in
  // column k.
  PySet(const std::vector<PySet*>& endpoints, std::vector<py::object> endpoint_objects,
        const py::array& connectivity, const std::string& name);
  // A scene's set, kept alive by `scene`.
  PySet(const scene::SetView& view, py::object scene);

  int size() const { return size_; }
  const std::string& name() const { return name_; }
  Set* owned() const { return owned_.get(); }
  const std::vector<Field>& fields() const { return fields_; }
  const Field& field(const std::string& name) const;
  Field& add_field(const std::string& name, const FieldType& type);
  int arity() const { return arity_; }
  const int32_t* endpoints() const { return endpoints_; }
  const int32_t* mesh_numbers() const { return mesh_numbers_; }

 private:
  std::unique_ptr<Set> owned_;
  std::vector<py::object> keep_;  // endpoint sets, or the scene
  std::string name_;
  int size_ = 0;
  int arity_ = 0;
  const int32_t* endpoints_ = nullptr;
  const int32_t* mesh_numbers_ = nullptr;
  std::vector<Field> fields_;
};

// Where programs print: Python's sys.stdout, a line at a time (flush() after a run for the
// text after the last newline).
std::ostream& python_stdout();
// Flushes python_stdout() when it goes out of scope (also when a run throws); construct it
// while holding the GIL, before releasing it.
struct FlushStdoutAtExit {
  ~FlushStdoutAtExit() { python_stdout().flush(); }
};

// Dense results as Python values: a number for a scalar, else an array sharing the result.
py::object to_python(const DenseResult& result);

void register_errors(py::module_& m);
void register_sets(py::module_& m);
void register_program(py::module_& m);
void register_scene(py::module_& m);
void register_mesh(py::module_& m);

}  // namespace simit::python
