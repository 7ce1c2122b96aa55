// simit.read_mesh: a mesh file's points and elements as numpy arrays.
#include <pybind11/stl.h>

#include "common.h"
#include "simit/mesh.h"

namespace simit::python {

namespace {

// An (n, K) array over a vector of K-arrays, which the array keeps alive; None when empty.
template <class T, size_t K>
py::object array_of(std::vector<std::array<T, K>>&& list, bool none_when_empty) {
  if (list.empty() && none_when_empty) return py::none();
  auto* owned = new std::vector<std::array<T, K>>(std::move(list));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<std::array<T, K>>*>(p); });
  const ComponentKind kind = std::is_same_v<T, double> ? ComponentKind::Float : ComponentKind::Int;
  return view_array({kind, {}, false}, {static_cast<py::ssize_t>(owned->size()), K},
                    owned->empty() ? nullptr : owned->front().data(), owner);
}

}  // namespace

void register_mesh(py::module_& m) {
  m.def(
      "read_mesh",
      [](py::object path) {
        const std::string p = py::str(py::module_::import("os").attr("fspath")(path));
        MeshData mesh;
        {
          py::gil_scoped_release release;
          mesh = read_mesh(p);
        }
        py::object out = py::module_::import("simit._mesh").attr("Mesh")();
        out.attr("path") = p;
        out.attr("points") = array_of(std::move(mesh.points), false);
        out.attr("tets") = array_of(std::move(mesh.tets), true);
        out.attr("triangles") = array_of(std::move(mesh.triangles), true);
        out.attr("edges") = array_of(std::move(mesh.edges), true);
        return out;
      },
      py::arg("path"),
      "Reads a TetGen (.node/.ele/.face/.edge), Gmsh (.msh) or Wavefront (.obj) mesh.");
}

}  // namespace simit::python
