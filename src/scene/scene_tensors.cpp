// Reading [tensors] into values of the extern tensors' types.
#include "scene/scene_tensors.h"

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "api/binding_check.h"
#include "api/set_access.h"
#include "api/tensor_values.h"

namespace simit::scene {

namespace ast = frontend::ast;
using frontend::Type;
using runtime::ComponentKind;
using runtime::FieldType;

namespace {

// The host storage one tensor's components are read into, in the layout a TensorSlot describes.
struct Storage {
  std::vector<double> doubles;
  std::vector<float> floats;
  std::vector<int32_t> ints;
  std::unique_ptr<bool[]> bools;
  TensorSlot slot(const FieldType& ft) {
    void* data = ft.kind == ComponentKind::Int    ? static_cast<void*>(ints.data())
                 : ft.kind == ComponentKind::Bool ? static_cast<void*>(bools.get())
                 : ft.single                      ? static_cast<void*>(floats.data())
                                                  : static_cast<void*>(doubles.data());
    return TensorSlot{api::host_kind(ft.kind), ft.single, ft.dims, data};
  }
};

std::vector<const toml::node*> flatten(const toml::node& value) {
  std::vector<const toml::node*> items;
  std::function<void(const toml::node&)> walk = [&](const toml::node& v) {
    if (const toml::array* a = v.as_array()) {
      for (const toml::node& item : *a) walk(item);
    } else {
      items.push_back(&v);
    }
  };
  walk(value);
  return items;
}

void read_component(const SceneFile& file, const std::string& what, const toml::node& v,
                    const FieldType& ft, size_t k, Storage& s) {
  switch (ft.kind) {
    case ComponentKind::Float:
      if (!v.is_number()) file.fail(&v, what + ": expected a number");
      s.doubles[k] = *v.value<double>();
      s.floats[k] = static_cast<float>(s.doubles[k]);
      break;
    case ComponentKind::Int:
      // Simit's int is 32 bits; TOML's integers are 64.
      if (!v.is_integer() || *v.value<int64_t>() < std::numeric_limits<int32_t>::min() ||
          *v.value<int64_t>() > std::numeric_limits<int32_t>::max())
        file.fail(&v, what + ": expected a whole number from " +
                          std::to_string(std::numeric_limits<int32_t>::min()) + " to " +
                          std::to_string(std::numeric_limits<int32_t>::max()));
      s.ints[k] = static_cast<int32_t>(*v.value<int64_t>());
      break;
    case ComponentKind::Bool:
      if (!v.is_boolean()) file.fail(&v, what + ": expected true or false");
      s.bools[k] = *v.value<bool>();
      break;
    default: break;
  }
}

interp::Value read_tensor(const SceneFile& file, const std::string& name, const ast::Variable& var,
                          const toml::node& value, bool float32) {
  const std::string what = "[tensors] " + name;
  const Type& type = *var.type;
  std::optional<FieldType> ft = api::field_type_for(type, float32 ? 4 : 8);
  if (!ft || ft->kind == ComponentKind::Complex || ft->kind == ComponentKind::String)
    file.fail(&value, what + ": extern '" + name + "' is " + frontend::to_string(type) +
                          ", which a scene cannot set (only int, float and bool tensors of "
                          "fixed size)");
  std::vector<const toml::node*> items = flatten(value);
  const size_t comps = ft->components();
  if (items.size() != comps)
    file.fail(&value, what + ": extern '" + name + "' is " + frontend::to_string(type) + " with " +
                          std::to_string(comps) + " component" + (comps == 1 ? "" : "s") +
                          ", but " + std::to_string(items.size()) + " value" +
                          (items.size() == 1 ? " was" : "s were") + " given");
  Storage s;
  switch (ft->kind) {
    case ComponentKind::Float:
      s.doubles.resize(comps);
      s.floats.resize(comps);
      break;
    case ComponentKind::Int: s.ints.resize(comps); break;
    case ComponentKind::Bool: s.bools = std::make_unique<bool[]>(comps); break;
    default: break;
  }
  const std::string typed = what + ": extern '" + name + "' is " + frontend::to_string(type);
  for (size_t k = 0; k < comps; ++k) read_component(file, typed, *items[k], *ft, k, s);
  return api::to_value(s.slot(*ft), type);
}

}  // namespace

std::map<std::string, SceneTensor> read_tensors(const SceneFile& file, bool float32) {
  std::map<std::string, SceneTensor> out;
  const toml::node* node = file.doc.get("tensors");
  if (!node) return out;
  const toml::table* t = node->as_table();
  if (!t) file.fail(node, "tensors: expected a table of extern tensor values");
  const std::map<std::string, const ast::Variable*> externs = program_externs(file, false);
  for (auto&& [key, value] : *t) {
    std::string name(key.str());
    auto ext = externs.find(name);
    if (ext == externs.end()) {
      std::string list;
      for (const auto& [n, v] : externs) list += (list.empty() ? "" : ", ") + n;
      file.fail(&value, "[tensors] " + name + ": the program declares no extern tensor '" + name +
                            "'" +
                            (list.empty() ? std::string(" (it declares none)")
                                          : " (its extern tensors: " + list + ")"));
    }
    out[name] = SceneTensor{ext->second, read_tensor(file, name, *ext->second, value, float32)};
  }
  return out;
}

}  // namespace simit::scene
