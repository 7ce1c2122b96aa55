// The variables a DAP client sees at a stop, as a tree: scopes of variables, tensors by
// component (blocks and rows first), sets by field, fields by element (paged), elements by
// field. References are valid until the run resumes (clear()).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "interp/value.h"
#include "repl/debugger.h"

namespace simit::runtime {
class Set;
}

namespace simit::dap {

class VariableStore {
 public:
  void clear() { nodes_.clear(); }
  // A scope (or any list of named values); its reference.
  int64_t add_scope(const std::vector<repl::VariableInfo>& vars);
  // The protocol's Variable for `value` named `name`, with a reference to its parts when it
  // has any.
  nlohmann::json variable(const std::string& name, const interp::Value* value,
                          const frontend::Type* type);
  // The children of `ref` from `start`, at most `count` (0: all); nullopt for an unknown
  // reference.
  std::optional<nlohmann::json> children(int64_t ref, int64_t start, int64_t count);

 private:
  struct Node {
    enum class Kind { Scope, Tensor, Set, Field, Element };
    Kind kind = Kind::Scope;
    std::vector<std::pair<std::string, std::optional<interp::Value>>> vars;  // Scope
    std::vector<const frontend::Type*> types;                                // Scope
    interp::Value value;                // Tensor, Element (the element value)
    const runtime::Set* set = nullptr;  // Set, Field, Element
    int field = -1;                     // Field
    int element = -1;                   // Element
  };
  int64_t add(Node node) {
    nodes_.push_back(std::move(node));
    return static_cast<int64_t>(nodes_.size());
  }
  nlohmann::json tensor_child(const runtime::Tensor& t, size_t index);
  nlohmann::json element_field(const runtime::Set& set, int field, int element);

  std::vector<Node> nodes_;  // reference r is nodes_[r - 1]
};

}  // namespace simit::dap
