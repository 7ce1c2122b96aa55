// The variable tree of a DAP stop: values shown as the terminal debugger prints them
// (repl/debug_values.h), their parts one level at a time.
#include "dap/variables.h"

#include <algorithm>
#include <cstring>

#include "interp/set_binding.h"
#include "repl/debug_values.h"
#include "runtime/set.h"

namespace simit::dap {

using json = nlohmann::json;
using interp::Value;
using runtime::Shape;
using runtime::Tensor;

namespace {

size_t bytes_per_component(runtime::ComponentKind kind) {
  switch (kind) {
    case runtime::ComponentKind::Int: return sizeof(int32_t);
    case runtime::ComponentKind::Float: return sizeof(double);
    case runtime::ComponentKind::Bool: return sizeof(bool);
    case runtime::ComponentKind::Complex: return sizeof(runtime::Complex);
    case runtime::ComponentKind::String: break;
  }
  return 0;
}

// `shape.size()` components of `t` from component `first`, as a tensor of `shape`.
Tensor slice(const Tensor& t, size_t first, const Shape& shape) {
  Tensor out(t.kind(), shape);
  const size_t bytes = bytes_per_component(t.kind());
  if (bytes && out.size())
    std::memcpy(out.mutable_ints(), reinterpret_cast<const std::byte*>(t.ints()) + first * bytes,
                out.size() * bytes);
  return out;
}

// How a tensor splits into children: blocks (blocked), rows (order >= 2) or components.
struct Parts {
  size_t count = 0;
  size_t stride = 1;  // components per child
  Shape shape;        // of a child (scalar: components)
};

Parts parts_of(const Tensor& t) {
  const Shape& s = t.shape();
  if (s.is_scalar() || !bytes_per_component(t.kind())) return {};
  if (s.is_blocked()) return {s.outer_count(), s.block_size(), s.block()};
  if (s.rank() >= 2) {
    std::vector<int> rest;
    for (int i = 1; i < s.rank(); ++i) rest.push_back(s.dim(i));
    return {static_cast<size_t>(s.dim(0)), s.size() / std::max(1, s.dim(0)), Shape::of(rest)};
  }
  return {s.size(), 1, Shape()};
}

}  // namespace

int64_t VariableStore::add_scope(const std::vector<repl::VariableInfo>& vars) {
  Node n;
  n.kind = Node::Kind::Scope;
  for (const repl::VariableInfo& v : vars) {
    n.vars.emplace_back(v.name, v.value ? std::optional<Value>(*v.value) : std::nullopt);
    n.types.push_back(v.type);
  }
  return add(std::move(n));
}

json VariableStore::variable(const std::string& name, const Value* value,
                             const frontend::Type* type) {
  json out = {{"name", name}, {"variablesReference", 0}};
  if (!value || value->kind() == Value::Kind::Empty) {
    out["value"] = "<no value>";
    return out;
  }
  out["value"] = repl::value_text(*value, type);
  if (type) out["type"] = frontend::to_string(*type);
  switch (value->kind()) {
    case Value::Kind::Tensor: {
      Tensor t = value->to_tensor();
      const Parts p = parts_of(t);
      if (p.count == 0) break;
      Node n;
      n.kind = Node::Kind::Tensor;
      n.value = *value;
      out["variablesReference"] = add(std::move(n));
      out["indexedVariables"] = p.count;
      break;
    }
    case Value::Kind::Set:
    case Value::Kind::Element: {
      const interp::SetBinding* b = value->binding();
      if (!b || !b->set) break;
      Node n;
      n.kind = value->kind() == Value::Kind::Set ? Node::Kind::Set : Node::Kind::Element;
      n.set = b->set;
      n.element = value->index();
      out["variablesReference"] = add(std::move(n));
      out["namedVariables"] = b->set->field_count();
      break;
    }
    default: break;
  }
  return out;
}

json VariableStore::tensor_child(const Tensor& t, size_t index) {
  const Parts p = parts_of(t);
  const std::string name = "[" + std::to_string(index) + "]";
  if (p.shape.is_scalar()) {
    const Value v = Value::component(t, index);
    return variable(name, &v, nullptr);
  }
  const Value v = Value::of_tensor(slice(t, index * p.stride, p.shape));
  return variable(name, &v, nullptr);
}

json VariableStore::element_field(const runtime::Set& set, int field, int element) {
  const Tensor t = set.get(field, element);
  const Value v = t.shape().is_scalar() ? Value::component(t, 0) : Value::of_tensor(t);
  return variable(set.field(field).name(), &v, nullptr);
}

std::optional<json> VariableStore::children(int64_t ref, int64_t start, int64_t count) {
  if (ref < 1 || ref > static_cast<int64_t>(nodes_.size())) return std::nullopt;
  // Copied: adding children's nodes may move the vector.
  const Node node = nodes_[static_cast<size_t>(ref - 1)];
  json list = json::array();
  auto range = [&](size_t total, auto&& make) {
    const size_t first = std::min<size_t>(static_cast<size_t>(std::max<int64_t>(0, start)), total);
    const size_t last =
        count > 0 ? std::min<size_t>(total, first + static_cast<size_t>(count)) : total;
    for (size_t i = first; i < last; ++i) list.push_back(make(i));
  };
  switch (node.kind) {
    case Node::Kind::Scope:
      range(node.vars.size(), [&](size_t i) {
        const auto& [name, value] = node.vars[i];
        return variable(name, value ? &*value : nullptr, node.types[i]);
      });
      break;
    case Node::Kind::Tensor: {
      const Tensor t = node.value.to_tensor();
      range(parts_of(t).count, [&](size_t i) { return tensor_child(t, i); });
      break;
    }
    case Node::Kind::Set:
      range(static_cast<size_t>(node.set->field_count()), [&](size_t i) {
        Node f;
        f.kind = Node::Kind::Field;
        f.set = node.set;
        f.field = static_cast<int>(i);
        const runtime::Field& field = node.set->field(f.field);
        json v = {
            {"name", field.name()},
            {"value", std::to_string(node.set->size()) + " elements (" + field.type().str() + ")"}};
        v["variablesReference"] = add(std::move(f));
        v["indexedVariables"] = node.set->size();
        return v;
      });
      break;
    case Node::Kind::Field:
      range(static_cast<size_t>(node.set->size()), [&](size_t i) {
        json v = element_field(*node.set, node.field, static_cast<int>(i));
        v["name"] = "[" + std::to_string(i) + "]";
        return v;
      });
      break;
    case Node::Kind::Element:
      range(static_cast<size_t>(node.set->field_count()),
            [&](size_t i) { return element_field(*node.set, static_cast<int>(i), node.element); });
      break;
  }
  return list;
}

}  // namespace simit::dap
