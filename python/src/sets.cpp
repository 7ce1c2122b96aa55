// simit.Set: vertex and edge sets made from Python (fixed size, pinned storage) or viewed in a
// scene, with every field a numpy array over the set's own storage.
#include <pybind11/stl.h>

#include "common.h"

namespace simit::python {

py::dtype dtype_of(ComponentKind kind, bool single) {
  switch (kind) {
    case ComponentKind::Int: return py::dtype::of<int32_t>();
    case ComponentKind::Float: return single ? py::dtype::of<float>() : py::dtype::of<double>();
    case ComponentKind::Bool: return py::dtype::of<bool>();
    case ComponentKind::Complex:
      return single ? py::dtype::of<std::complex<float>>() : py::dtype::of<std::complex<double>>();
  }
  throw Error("unknown component kind");
}

FieldType field_type_of(const py::handle& spec, const std::vector<int>& dims) {
  py::module_ builtins = py::module_::import("builtins");
  if (spec.is(builtins.attr("float"))) return {ComponentKind::Float, dims, false};
  if (spec.is(builtins.attr("int"))) return {ComponentKind::Int, dims, false};
  if (spec.is(builtins.attr("bool"))) return {ComponentKind::Bool, dims, false};
  if (spec.is(builtins.attr("complex"))) return {ComponentKind::Complex, dims, false};
  py::dtype d;
  try {
    d = py::dtype::from_args(py::reinterpret_borrow<py::object>(spec));
  } catch (const py::error_already_set&) {
    throw Error("'" + std::string(py::str(spec)) + "' is not a dtype");
  }
  for (ComponentKind k :
       {ComponentKind::Float, ComponentKind::Int, ComponentKind::Bool, ComponentKind::Complex})
    for (bool single : {false, true})
      if (d.equal(dtype_of(k, single)) &&
          (single == false || k == ComponentKind::Float || k == ComponentKind::Complex))
        return {k, dims, single};
  throw Error("dtype " + py::str(py::handle(d)).cast<std::string>() +
              " is not a Simit component: use float (float64, or float32 for programs run "
              "with float32=True), int (int32), bool or complex (complex128, complex64)");
}

py::array view_array(const FieldType& type, std::vector<py::ssize_t> dims, void* data,
                     py::handle base, bool writeable) {
  const py::dtype dt = dtype_of(type.kind, type.single);
  std::vector<py::ssize_t> strides(dims.size());
  py::ssize_t stride = dt.itemsize();
  for (size_t i = dims.size(); i-- > 0;) {
    strides[i] = stride;
    stride *= dims[i];
  }
  py::array a(dt, dims, strides, data, base);
  if (!writeable) a.attr("flags").attr("writeable") = false;
  return a;
}

PySet::PySet(int size, const std::string& name) : name_(name), size_(size) {
  if (size < 0) throw Error("a set's size cannot be negative (" + std::to_string(size) + ")");
  owned_ = std::make_unique<Set>(name);
  owned_->add_many(size);
  owned_->pin_fields();
}

PySet::PySet(const std::vector<PySet*>& endpoints, std::vector<py::object> endpoint_objects,
             const py::array& connectivity, const std::string& name)
    : keep_(std::move(endpoint_objects)), name_(name) {
  if (endpoints.empty()) throw Error("an edge set needs at least one endpoint set");
  std::vector<Set*> sets;
  for (size_t k = 0; k < endpoints.size(); ++k) {
    if (!endpoints[k]->owned())
      throw Error("endpoint set " + std::to_string(k) + " belongs to a scene; the endpoints of " +
                  "a set made in Python must be made in Python too");
    sets.push_back(endpoints[k]->owned());
  }
  const int arity = static_cast<int>(endpoints.size());
  if (!py::isinstance<py::array>(connectivity) ||
      (py::str(connectivity.dtype().attr("kind")).cast<std::string>() != "i" &&
       py::str(connectivity.dtype().attr("kind")).cast<std::string>() != "u"))
    throw Error("connectivity must be an integer array of shape (n, " + std::to_string(arity) +
                "), not " + py::str(py::handle(connectivity.dtype())).cast<std::string>());
  if (connectivity.ndim() != 2 || connectivity.shape(1) != arity)
    throw Error("connectivity must have shape (n, " + std::to_string(arity) +
                ") (one column per endpoint set), not " +
                std::string(py::str(connectivity.attr("shape"))));
  auto c = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(connectivity);
  const auto rows = c.shape(0);
  const int64_t* v = c.data();
  for (py::ssize_t r = 0; r < rows; ++r)
    for (int k = 0; k < arity; ++k) {
      const int64_t e = v[r * arity + k];
      if (e < 0 || e >= endpoints[k]->size())
        throw Error(
            "connectivity[" + std::to_string(r) + ", " + std::to_string(k) +
            "] = " + std::to_string(e) + " is not an element of endpoint set " + std::to_string(k) +
            (endpoints[k]->name().empty() ? std::string() : " '" + endpoints[k]->name() + "'") +
            " (" + std::to_string(endpoints[k]->size()) + " elements)");
    }
  owned_ = std::make_unique<Set>(name, sets);
  std::vector<ElementRef> ends(arity);
  for (py::ssize_t r = 0; r < rows; ++r) {
    for (int k = 0; k < arity; ++k) ends[k] = ElementRef(static_cast<int>(v[r * arity + k]));
    owned_->add(std::span<const ElementRef>(ends));
  }
  owned_->pin_fields();
  size_ = owned_->size();
  arity_ = arity;
  endpoints_ = owned_->endpoints_data();
}

PySet::PySet(const scene::SetView& view, py::object scene)
    : keep_{std::move(scene)},
      name_(view.name),
      size_(view.size),
      arity_(view.arity),
      endpoints_(view.endpoints),
      mesh_numbers_(view.mesh_numbers) {
  for (const scene::FieldView& f : view.fields) fields_.push_back({f.name, f.type, f.data});
}

const PySet::Field& PySet::field(const std::string& name) const {
  for (const Field& f : fields_)
    if (f.name == name) return f;
  std::string known;
  for (const Field& f : fields_) known += (known.empty() ? "" : ", ") + f.name;
  throw py::key_error("set" + (name_.empty() ? std::string() : " '" + name_ + "'") +
                      " has no field '" + name + "'" +
                      (known.empty() ? std::string(" (it has none)") : " (it has " + known + ")"));
}

PySet::Field& PySet::add_field(const std::string& name, const FieldType& type) {
  if (!owned_) throw Error("the fields of a scene's set are the program's: none can be added");
  for (int d : type.dims)
    if (d <= 0) throw Error("field '" + name + "': dimensions must be positive");
  owned_->add_field(name, type);
  fields_.push_back({name, type, owned_->field_data(name)});
  return fields_.back();
}

namespace {

py::array field_view(py::object self, const PySet::Field& f) {
  const PySet& s = self.cast<const PySet&>();
  std::vector<py::ssize_t> dims{s.size()};
  for (int d : f.type.dims) dims.push_back(d);
  return view_array(f.type, dims, f.data, self);
}

std::vector<int> dims_of(const py::object& shape) {
  std::vector<int> dims;
  if (py::isinstance<py::int_>(shape)) return {shape.cast<int>()};
  for (py::handle d : shape) dims.push_back(d.cast<int>());
  return dims;
}

}  // namespace

void register_sets(py::module_& m) {
  py::class_<PySet>(m, "Set", R"(A set of elements: Set(size) for vertices, or
Set(endpoints=(a, b, ...), connectivity=array of shape (n, arity)) for edges. Its size is
fixed: fields are numpy views of storage that never moves.)")
      .def(py::init([](std::optional<int> size, std::optional<py::tuple> endpoints,
                       std::optional<py::object> connectivity, const std::string& name) {
             if (endpoints || connectivity) {
               if (size) throw Error("give a size (vertex set) or endpoints (edge set), not both");
               if (!endpoints || !connectivity)
                 throw Error("an edge set needs both endpoints=(...) and connectivity=array");
               std::vector<PySet*> sets;
               std::vector<py::object> objects;
               for (py::handle e : *endpoints) {
                 if (!py::isinstance<PySet>(e))
                   throw Error("endpoints must be simit.Set objects, not " +
                               std::string(py::str(py::type::of(e))));
                 sets.push_back(&e.cast<PySet&>());
                 objects.push_back(py::reinterpret_borrow<py::object>(e));
               }
               // Any array-like (a list of rows too); its dtype is checked below.
               const py::array rows = py::module_::import("numpy").attr("asarray")(*connectivity);
               return std::make_unique<PySet>(sets, objects, rows, name);
             }
             if (!size) throw Error("Set(size) or Set(endpoints=..., connectivity=...)");
             return std::make_unique<PySet>(*size, name);
           }),
           py::arg("size") = py::none(), py::kw_only(), py::arg("endpoints") = py::none(),
           py::arg("connectivity") = py::none(), py::arg("name") = "")
      .def("__len__", &PySet::size)
      .def_property_readonly("name", &PySet::name)
      .def(
          "add_field",
          [](py::object self, const std::string& name, py::object dtype, py::object shape) {
            PySet& s = self.cast<PySet&>();
            return field_view(self, s.add_field(name, field_type_of(dtype, dims_of(shape))));
          },
          py::arg("name"), py::arg("dtype") = py::float_().get_type(),
          py::arg("shape") = py::tuple(),
          "Adds a field (zero for every element) and returns its view.")
      .def("__getitem__",
           [](py::object self, const std::string& name) {
             return field_view(self, self.cast<PySet&>().field(name));
           })
      .def("__contains__",
           [](const PySet& s, const std::string& name) {
             for (const auto& f : s.fields())
               if (f.name == name) return true;
             return false;
           })
      .def("fields",
           [](const PySet& s) {
             std::vector<std::string> names;
             for (const auto& f : s.fields()) names.push_back(f.name);
             return names;
           })
      .def_property_readonly("endpoints",
                             [](py::object self) -> py::object {
                               const PySet& s = self.cast<const PySet&>();
                               if (s.arity() == 0) return py::none();
                               return view_array({ComponentKind::Int, {}, false},
                                                 {s.size(), s.arity()},
                                                 const_cast<int32_t*>(s.endpoints()), self, false);
                             })
      .def_property_readonly("mesh_numbers",
                             [](py::object self) -> py::object {
                               const PySet& s = self.cast<const PySet&>();
                               if (!s.mesh_numbers()) return py::none();
                               return view_array({ComponentKind::Int, {}, false}, {s.size()},
                                                 const_cast<int32_t*>(s.mesh_numbers()), self,
                                                 false);
                             })
      .def("__repr__", [](const PySet& s) {
        std::string r = "simit.Set(";
        if (!s.name().empty()) r += "'" + s.name() + "', ";
        r += std::to_string(s.size()) + " elements";
        if (s.arity()) r += ", arity " + std::to_string(s.arity());
        for (const auto& f : s.fields()) r += ", " + f.name;
        return r + ")";
      });
}

}  // namespace simit::python
