// Semantic types of LANGUAGE.md §5: scalars, (blocked) tensors over integer and set
// dimensions, elements with their source set, sets, grids, tuples, opaque handles.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace simit::frontend {

namespace ast {
struct ElementDecl;
struct Variable;
}  // namespace ast

struct Type;
using TypeRef = std::shared_ptr<const Type>;

enum class ScalarKind { Int, Float, Bool, Complex, String };

// One dimension of a tensor: a fixed size, a set, or a generic parameter of a function.
struct IndexSet {
  enum class Kind { Fixed, Set, Generic };
  Kind kind = Kind::Fixed;
  int size = 0;                        // Fixed
  const ast::Variable* var = nullptr;  // Set: the extern or parameter naming the set;
                                       // Generic: the generic parameter
  static IndexSet fixed(int n) { return {Kind::Fixed, n, nullptr}; }
  static IndexSet set(const ast::Variable* v) { return {Kind::Set, 0, v}; }
  static IndexSet generic(const ast::Variable* v) { return {Kind::Generic, 0, v}; }
  bool operator==(const IndexSet& o) const;
  bool operator!=(const IndexSet& o) const { return !(*this == o); }
};

struct Type {
  enum class Kind {
    Void,  // the value of a call with no results
    Scalar,
    Tensor,  // order >= 1
    Element,
    Set,  // vertex or edge set (grid sets too, with grid_dims > 0)
    Tuple,
    Opaque,
    Multi,  // the values of a call or map with several results
  };
  Kind kind = Kind::Void;

  ScalarKind scalar = ScalarKind::Float;  // Scalar

  // Tensor: outer dimensions, block type (a Scalar, or a Tensor of the same order), and
  // for order 1 the orientation.
  std::vector<IndexSet> dims;
  TypeRef block;
  bool row = false;

  // Element: its declaration and, when known (§8.5.6), the set it comes from
  // (Kind::Set or Kind::Generic index set; kind Fixed with size 0 means unknown).
  const ast::ElementDecl* element = nullptr;
  IndexSet source;
  bool has_source = false;

  // Set: element type (`element`), endpoint sets in order (empty for vertex sets);
  // grids: grid_dims > 0 and endpoints = {point set}.
  std::vector<IndexSet> endpoints;
  int grid_dims = 0;

  // Tuple: component element types; names empty for unnamed tuples.
  // Multi: the result types.
  std::vector<TypeRef> members;
  std::vector<std::string> names;

  bool is_scalar() const { return kind == Kind::Scalar; }
  bool is_tensor() const { return kind == Kind::Tensor || kind == Kind::Scalar; }
  int order() const { return kind == Kind::Tensor ? static_cast<int>(dims.size()) : 0; }
  // The scalar component type of a scalar or (blocked) tensor.
  ScalarKind component() const;
  // True when any dimension (at any blocking level) is a set or generic parameter.
  bool is_global() const;
};

TypeRef make_void();
TypeRef make_scalar(ScalarKind k);
TypeRef make_tensor(std::vector<IndexSet> dims, TypeRef block, bool row = false);
TypeRef make_opaque();
TypeRef make_multi(std::vector<TypeRef> members);

// Type equality of LANGUAGE.md §10.2.
bool types_equal(const Type& a, const Type& b);
// Readable spelling, e.g. `vector[nodes](vector[3](float))'`.
std::string to_string(const Type& t);
std::string to_string(ScalarKind k);

}  // namespace simit::frontend
